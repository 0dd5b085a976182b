#include "session/stages/forearm_report.hpp"

#include <cmath>

#include "forearm/orientation_uncertainty.hpp"
#include "session/stages/proto_values.hpp"

namespace posefuse::session {

void report_clock(const std::string& device_id, const sync::LinearClock& camera_from_device, double first_device_us,
                  v1::CalibrationReport& report) {
  (*report.mutable_clock_offset_us())[device_id] =
      std::llround(camera_from_device.to_reference_us(first_device_us) - first_device_us);
  (*report.mutable_clock_offset_sigma_us())[device_id] = camera_from_device.sigma_us(first_device_us);
  (*report.mutable_clock_drift_ppm())[device_id] = camera_from_device.drift * 1e6;
}

void report_forearm_model(const std::string& device_id, forearm::Side side, const forearm::ForearmCalibration& c,
                          bool has_model, std::uint32_t strap_frames, v1::CalibrationReport& report) {
  v1::ForearmModel& model = *report.add_forearms();
  model.set_arm(to_proto_arm(side));
  model.set_device_id(device_id);
  model.set_r_m(has_model ? c.model.r_m : 0.0);
  model.set_d_se_m(has_model ? c.model.d_se_m : 0.0);
  model.set_d_sw_m(has_model ? c.model.d_sw_m : 0.0);
  model.set_d_ul_m(c.model.d_ul_m);
  model.set_d_ul_uncertainty_m(c.d_ul_uncertainty_m);
  *model.mutable_a_from_f() = to_proto(forearm::Quat(c.model.F_from_A.conjugate()));
  model.set_estimated(true);
  model.set_calibration_frames(static_cast<std::uint32_t>(c.frame_count));
  model.set_a_from_f_spread_rad(c.F_from_A_spread_rad);
  model.set_strap_frames(strap_frames);
  model.set_mounting_source(v1::ForearmModel::CALIBRATION_POSE);
  model.set_orientation_uncertainty_rad(forearm::pose_calibration_rms_rad(c.F_from_A_spread_rad));
}

void report_motion_mounting(const std::string& device_id, forearm::Side side, const forearm::MountingEstimate& m,
                            v1::CalibrationReport& report) {
  v1::ForearmModel& model = *report.add_forearms();
  model.set_arm(to_proto_arm(side));
  model.set_device_id(device_id);
  *model.mutable_a_from_f() = to_proto(forearm::Quat(m.F_from_A.conjugate()));
  model.set_estimated(true);
  model.set_mounting_source(v1::ForearmModel::MOTION);
  model.set_orientation_uncertainty_rad(forearm::orientation_rms_rad(m.axis_rms_rad, m.roll_rms_rad));
  model.set_axis_uncertainty_rad(m.axis_rms_rad);
  model.set_roll_uncertainty_rad(m.roll_rms_rad);
  model.set_mounting_frames(static_cast<std::uint32_t>(m.frames));
  model.set_hinge_frames(static_cast<std::uint32_t>(m.hinge_frames));
  model.set_mounting_seconds(m.seconds);
  model.set_roll_limit(m.roll_limit);
}

}  // namespace posefuse::session
