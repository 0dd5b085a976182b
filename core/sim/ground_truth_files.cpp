#include "sim/ground_truth_files.hpp"

#include <sstream>

#include "common/error.hpp"
#include "session/file_bytes.hpp"
#include "session/result_encoder.hpp"
#include "session/result_files.hpp"
#include "session/text_fields.hpp"
#include "sim/angle_truth.hpp"

namespace posefuse::sim {
namespace {

using session::format_double;

void set_quat(const Quat& q, v1::Quaternion* out) {
  out->set_w(q.w());
  out->set_x(q.x());
  out->set_y(q.y());
  out->set_z(q.z());
}

void set_vec(const Vec3& v, v1::Vec3* out) {
  out->set_x(v.x());
  out->set_y(v.y());
  out->set_z(v.z());
}

v1::Arm arm_enum(int arm) { return arm == 0 ? v1::LEFT : v1::RIGHT; }

}  // namespace

std::string json_vec(const Vec3& v) {
  return "[" + format_double(v.x()) + ", " + format_double(v.y()) + ", " + format_double(v.z()) + "]";
}
std::string json_quat(const Quat& q) {
  return "[" + format_double(q.w()) + ", " + format_double(q.x()) + ", " + format_double(q.y()) + ", " +
         format_double(q.z()) + "]";
}

namespace {

std::string json_mat(const Eigen::Matrix3d& m) {
  std::string out = "[";
  for (int r = 0; r < 3; ++r) out += (r ? ", " : "") + json_vec(m.row(r).transpose());
  return out + "]";
}

v1::CalibrationReport calibration_report(const SimTruth& truth) {
  v1::CalibrationReport report;
  const double field_uT = truth.options.imu.synth.earth_field.m_W_uT().norm();
  for (const SimDeviceTruth& device : truth.devices) {
    auto* imu = report.add_imus();
    imu->set_device_id(device.device_id);
    imu->set_mag_fit_residual(0.0);
    imu->set_mag_field_ut(field_uT);
    imu->set_mag_coverage(1.0);
    set_vec(device.errors.gyr_bias_rad_s, imu->mutable_gyro_bias_rad_s());
    imu->set_calibrated(true);
    // camera_t_us = device_t_us + offset_us at camera time 0 (drift in truth.json).
    (*report.mutable_clock_offset_us())[device.device_id] = -std::llround(device.clock.offset_s * 1e6);
  }
  report.set_buzzer_tone_hz(truth.options.buzzer.tone_hz);  // every session has its buzzer
  for (const SimArmTruth& arm : truth.arms) {
    if (!arm.has_imu) continue;
    auto* forearm = report.add_forearms();
    forearm->set_arm(arm_enum(arm.arm));
    forearm->set_r_m(arm.r_m);
    forearm->set_d_se_m(arm.d_se_m);
    forearm->set_d_sw_m(arm.d_sw_m);
    forearm->set_d_ul_m(arm.d_ul_m);
    set_quat(arm.F_from_A.conjugate(), forearm->mutable_a_from_f());
    forearm->set_estimated(true);
  }
  auto* shape = report.mutable_body_shape();
  for (int i = 0; i < truth.options.betas.size(); ++i) shape->add_betas(truth.options.betas[i]);
  const Eigen::Matrix3Xd& j = truth.rest_joints;
  const auto length = [&](int a, int b) { return (j.col(a) - j.col(b)).norm(); };
  shape->set_upper_arm_length_left_m(length(body::kLeftShoulder, body::kLeftElbow));
  shape->set_upper_arm_length_right_m(length(body::kRightShoulder, body::kRightElbow));
  shape->set_forearm_length_left_m(length(body::kLeftElbow, body::kLeftWrist));
  shape->set_forearm_length_right_m(length(body::kRightElbow, body::kRightWrist));
  shape->set_shoulder_width_m(length(body::kLeftShoulder, body::kRightShoulder));
  shape->set_torso_length_m(length(body::kPelvis, body::kNeck));
  shape->set_estimated(true);
  set_quat(truth.K_from_W, report.mutable_k_from_w());
  return report;
}

std::string truth_json(const SimTruth& truth) {
  const SimSessionOptions& o = truth.options;
  std::ostringstream s;
  s << "{\n  \"seed\": " << o.seed << ",\n  \"duration_s\": " << format_double(o.duration_s) << ",\n  \"motion\": \""
    << o.motion << "\",\n  \"frames\": {\n"
    << "    \"K_from_W\": " << json_quat(truth.K_from_W) << ",\n"
    << "    \"W_from_Body\": " << json_quat(truth.W_from_Body) << ",\n"
    << "    \"K_from_Body_rotation\": " << json_quat(Quat(truth.K_from_Body.linear())) << ",\n"
    << "    \"K_from_Body_translation_m\": " << json_vec(truth.K_from_Body.translation()) << ",\n"
    << "    \"K_from_B\": " << json_quat(truth.K_from_B) << ",\n"
    << "    \"camera_p_W_m\": " << json_vec(truth.camera_p_W_m) << ",\n"
    << "    \"color_from_depth_rotation\": " << json_quat(Quat(o.color_camera.color_from_depth.linear())) << ",\n"
    << "    \"color_from_depth_translation_m\": " << json_vec(o.color_camera.color_from_depth.translation())
    << "\n  },\n  \"earth_field_W_uT\": " << json_vec(o.imu.synth.earth_field.m_W_uT())
    << ",\n  \"gravity_m_s2\": " << format_double(o.imu.synth.gravity_m_s2) << ",\n  \"arms\": [";
  bool first = true;
  for (const SimArmTruth& arm : truth.arms) {
    if (!arm.has_imu) continue;
    s << (first ? "" : ",") << "\n    {\"arm\": \"" << (arm.arm == 0 ? "LEFT" : "RIGHT") << "\", \"device_id\": \""
      << arm.device_id << "\", \"r_m\": " << format_double(arm.r_m) << ", \"d_se_m\": " << format_double(arm.d_se_m)
      << ", \"d_sw_m\": " << format_double(arm.d_sw_m) << ", \"d_ul_m\": " << format_double(arm.d_ul_m)
      << ", \"F_from_A\": " << json_quat(arm.F_from_A)
      << ", \"strap_width_m\": " << format_double(o.color_camera.strap_width_m) << ", \"strap_slip_max_rotation_rad\": "
      << format_double(o.strap_slip.enabled ? o.strap_slip.max_rotation_rad : 0.0)
      << ", \"strap_slip_max_slide_m\": " << format_double(o.strap_slip.enabled ? o.strap_slip.max_slide_m : 0.0)
      << "}";
    first = false;
  }
  s << "\n  ],\n  \"devices\": [";
  first = true;
  for (const SimDeviceTruth& d : truth.devices) {
    const ImuErrors& e = d.errors;
    s << (first ? "" : ",") << "\n    {\"device_id\": \"" << d.device_id << "\", \"role\": \""
      << v1::ImuDevice::Role_Name(d.role) << "\", \"clock_offset_s\": " << format_double(d.clock.offset_s)
      << ", \"clock_drift\": " << format_double(d.clock.drift)
      << ",\n     \"gyr_bias_rad_s\": " << json_vec(e.gyr_bias_rad_s)
      << ", \"gyr_scale_misalignment\": " << json_mat(e.gyr_scale_misalignment)
      << ",\n     \"acc_bias_m_s2\": " << json_vec(e.acc_bias_m_s2)
      << ", \"acc_scale_misalignment\": " << json_mat(e.acc_scale_misalignment)
      << ",\n     \"hard_iron_uT\": " << json_vec(e.hard_iron_uT) << ", \"soft_iron\": " << json_mat(e.soft_iron)
      << ",\n     \"gyr_bias_per_kelvin_rad_s\": " << json_vec(e.gyr_bias_per_kelvin_rad_s)
      << ", \"acc_bias_per_kelvin_m_s2\": " << json_vec(e.acc_bias_per_kelvin_m_s2)
      << ",\n     \"gyr_scale_per_kelvin\": " << json_vec(e.gyr_scale_per_kelvin)
      << ", \"acc_scale_per_kelvin\": " << json_vec(e.acc_scale_per_kelvin) << "}";
    first = false;
  }
  s << "\n  ],\n  \"buzzer_stop_camera_s\": " << format_double(truth.buzzer_stop_camera_s)
    << ",\n  \"buzzer_heard_camera_s\": " << format_double(truth.buzzer_heard_camera_s)
    << ",\n  \"buzzer_later_stops_camera_s\": [";
  for (std::size_t i = 0; i < truth.buzzer_later_stops_camera_s.size(); ++i) {
    s << (i ? ", " : "") << format_double(truth.buzzer_later_stops_camera_s[i]);
  }
  s << "],\n  \"ble_broadcast_camera_s\": [";
  for (std::size_t i = 0; i < truth.ble_broadcast_camera_s.size(); ++i) {
    s << (i ? ", " : "") << format_double(truth.ble_broadcast_camera_s[i]);
  }
  s << "]\n}\n";
  return s.str();
}

}  // namespace

void write_ground_truth(const SimTruth& truth, const std::filesystem::path& directory) {
  if (std::filesystem::exists(directory) && !std::filesystem::is_empty(directory)) {
    throw Error(ErrorCode::kFailedPrecondition, directory.string(), "exists and is not empty");
  }
  session::ResultFiles files(directory);
  for (const SimFrameTruth& frame : truth.frames) {
    v1::FrameResult result;
    result.set_t_us(frame.t_us);
    const auto add_joints = [](const Eigen::Matrix3Xd& joints, auto* list) {
      for (int j = 0; j < joints.cols(); ++j) {
        auto* joint = list->Add();
        set_vec(joints.col(j), joint->mutable_position_m());
        joint->set_source(v1::GROUND_TRUTH);
        joint->set_confidence(1.0);
      }
    };
    add_joints(frame.smpl_joints_K, result.mutable_smpl_joints());
    add_joints(frame.camera_joints_K, result.mutable_camera_joints());
    for (const SimArmTruth& arm : truth.arms) {
      if (!arm.has_imu) continue;
      const auto a = static_cast<std::size_t>(arm.arm);
      auto* forearm = result.add_forearms();
      forearm->set_arm(arm_enum(arm.arm));
      set_quat(frame.K_from_F[a], forearm->mutable_k_from_f());
      forearm->set_pronation_rad(frame.pronation_rad[a]);
      forearm->set_source(v1::GROUND_TRUTH);
      forearm->set_confidence(1.0);
    }
    for (std::size_t d = 0; d < truth.devices.size(); ++d) {
      auto* position = result.add_imu_positions();
      position->set_device_id(truth.devices[d].device_id);
      set_vec(frame.imu_p_K[d], position->mutable_position_m());
      position->set_source(v1::GROUND_TRUTH);
    }
    files.write_frame(result);
  }
  const AngleTruth angles = angle_truth(truth);
  for (std::size_t f = 0; f < truth.frames.size(); ++f) {
    const auto result =
        session::encode_value(session::FrameAngles{truth.frames[f].t_us, angles.frames[f], v1::GROUND_TRUTH});
    files.write_angles(result->joint_angles());
  }
  if (angles.repetitions)
    files.write_repetitions(session::encode_value(session::Repetitions{*angles.repetitions})->repetitions());
  for (const SimDeviceTruth& device : truth.devices) {
    v1::ImuOrientationBatch batch;
    batch.set_device_id(device.device_id);
    for (std::size_t i = 0; i < device.t_device_us.size(); ++i) {
      batch.add_t_us(device.t_device_us[i]);
      const Quat& q = device.W_from_A[i];
      for (double c : {q.w(), q.x(), q.y(), q.z()}) batch.add_w_from_a(c);
      batch.add_uncertainty_rad(0.0);  // the truth
      batch.add_confidence(1.0);
    }
    files.write_orientations(batch);
    if (device.K_from_F.empty()) continue;
    v1::ForearmOrientationBatch forearm;
    forearm.set_device_id(device.device_id);
    forearm.set_arm(device.role == v1::ImuDevice::ARM_LEFT ? v1::LEFT : v1::RIGHT);
    for (std::size_t i = 0; i < device.K_from_F.size(); ++i) {
      forearm.add_t_us(std::llround(device.t_camera_s[i] * 1e6));
      const Quat& q = device.K_from_F[i];
      for (double c : {q.w(), q.x(), q.y(), q.z()}) forearm.add_k_from_f(c);
      forearm.add_pronation_rad(device.pronation_rad[i]);
      forearm.add_uncertainty_rad(0.0);  // the truth
      forearm.add_confidence(1.0);
    }
    files.write_forearm_orientations(forearm);
  }
  files.write_calibration(calibration_report(truth));
  files.close();

  session::CsvWriter occlusion(directory / "occlusion.csv",
                               {"t_us", "arm", "forearm_visible_fraction", "forearm_occluded", "strap_visible"});
  for (const SimFrameTruth& frame : truth.frames) {
    for (const SimArmTruth& arm : truth.arms) {
      const auto a = static_cast<std::size_t>(arm.arm);
      occlusion.row({std::to_string(frame.t_us), v1::Arm_Name(arm_enum(arm.arm)),
                     format_double(frame.forearm_visible_fraction[a]),
                     frame.forearm_visible_fraction[a] < 0.5 ? "1" : "0", frame.strap_visible[a] ? "1" : "0"});
    }
  }
  occlusion.close();
  std::filesystem::create_directories(directory / "imu_samples");
  for (const SimDeviceTruth& device : truth.devices) {
    session::CsvWriter csv(directory / "imu_samples" / (device.device_id + ".csv"),
                           {"t_device_us", "t_camera_us", "lost", "bias_gx", "bias_gy", "bias_gz"});
    for (std::size_t i = 0; i < device.t_device_us.size(); ++i) {
      const Vec3& b = device.gyr_bias_rad_s[i];
      csv.row({std::to_string(device.t_device_us[i]), std::to_string(std::llround(device.t_camera_s[i] * 1e6)),
               device.lost[i] ? "1" : "0", format_double(b.x()), format_double(b.y()), format_double(b.z())});
    }
    csv.close();
  }
  session::write_file_bytes(directory / "truth.json", truth_json(truth));
}

}  // namespace posefuse::sim
