#include "session/stages/imu_orientation_stage.hpp"

#include <cmath>
#include <limits>

#include "common/error.hpp"
#include "common/number_text.hpp"
#include "geometry/quaternion.hpp"
#include "session/stages/imu_options.hpp"
#include "session/stages/proto_values.hpp"

namespace posefuse::session {

std::string_view ImuOrientationStage::description() const {
  return "orientation W_from_A of every IMU sample (robust 9-axis filter), gyro bias per device";
}

const OptionTable& ImuOrientationStage::options() const { return imu_option_table(); }

void ImuOrientationStage::start(const v1::SessionHeader& header, StageOutput& /*out*/) {
  const ImuOptions options = read_imu_options(header);
  for (const v1::ImuDevice& device : header.imu_devices()) {
    device_order_.push_back(device.device_id());
    Device state{imu::RobustOrientationFilter(options.filter)};
    if (const auto it = options.mag_calibrations.find(device.device_id()); it != options.mag_calibrations.end()) {
      state.mag_calibration = it->second;
    }
    devices_.emplace(device.device_id(), std::move(state));
  }
}

void ImuOrientationStage::on_imu(const ImuBlock& block, StageOutput& out) {
  const auto it = devices_.find(block.device_id);
  if (it == devices_.end()) {
    // The validator rejects unknown devices; reaching this is a bug of ours.
    throw Error(ErrorCode::kInternal, "imu.device_id", "'" + block.device_id + "' has no filter");
  }
  Device& device = it->second;
  ImuOrientations orientations{block.device_id, block.samples, {}, {}};
  orientations.W_from_A.reserve(block.samples.size());
  orientations.uncertainty_rad.reserve(block.samples.size());
  for (imu::ImuSample& sample : orientations.samples) {
    if (device.mag_calibration) sample.mag_uT = device.mag_calibration->apply(sample.mag_uT);  // eq. 3
    const imu::Quat W_from_A = geometry::same_hemisphere(device.filter.update(sample), device.last_W_from_A);
    device.last_W_from_A = W_from_A;
    orientations.W_from_A.push_back(W_from_A);
    orientations.uncertainty_rad.push_back(device.filter.orientation_uncertainty_rad());
  }
  device.samples += block.samples.size();
  out.hand_on(std::move(orientations));
}

void ImuOrientationStage::finish(StageOutput& out) {
  for (std::size_t i = 0; i < device_order_.size(); ++i) {
    const std::string& id = device_order_[i];
    const Device& device = devices_.at(id);
    v1::ImuCalibration& calibration = *out.calibration().add_imus();
    calibration.set_device_id(id);
    calibration.set_mag_fit_residual(std::numeric_limits<double>::quiet_NaN());
    calibration.set_mag_coverage(0.0);
    calibration.set_calibrated(device.mag_calibration.has_value());
    if (device.samples == 0) {
      calibration.set_mag_field_ut(std::numeric_limits<double>::quiet_NaN());
      out.warn("IMU_NO_SAMPLES", "header.imu_devices[" + std::to_string(i) + "]",
               "device '" + id + "' sent no samples; no orientation or gyro bias for it");
      continue;
    }
    if (device.filter.gaps() > 0) {
      out.warn("IMU_SAMPLES_LOST", "imu[" + id + "]",
               "device '" + id + "' lost samples " + std::to_string(device.filter.gaps()) + " times (" +
                   fixed_text(device.filter.lost_s(), 2) +
                   " s in all); its orientations after each are uncertain until the filter has recovered "
                   "(its orientations and forearm orientations carry that uncertainty, docs/imu-robust.md)");
    }
    calibration.set_mag_field_ut(device.filter.mag_ref_norm_uT() > 0.0 ? device.filter.mag_ref_norm_uT()
                                                                       : std::numeric_limits<double>::quiet_NaN());
    *calibration.mutable_gyro_bias_rad_s() = to_proto(device.filter.gyro_bias_rad_s());
  }
}

}  // namespace posefuse::session
