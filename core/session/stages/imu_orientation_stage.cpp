#include "session/stages/imu_orientation_stage.hpp"

#include <cmath>
#include <limits>

#include "common/error.hpp"
#include "geometry/quaternion.hpp"
#include "session/mag_calibration_option.hpp"
#include "session/stages/proto_values.hpp"
#include "session/text_fields.hpp"

namespace posefuse::session {

namespace {

constexpr const char* kTauAccKey = "imu.tau_acc_s";
constexpr const char* kTauMagKey = "imu.tau_mag_s";

// A positive, finite time constant from the header options, or `fallback` when absent.
double time_constant_option(const v1::SessionHeader& header, const char* key, double fallback) {
  const auto it = header.options().find(key);
  if (it == header.options().end()) return fallback;
  const std::string field = std::string("header.options[") + key + "]";
  const double value = parse_double(it->second, field);
  if (!std::isfinite(value) || value <= 0.0) {
    throw_invalid(field, "is '" + it->second + "', must be a positive number of seconds");
  }
  return value;
}

}  // namespace

std::string_view ImuOrientationStage::description() const {
  return "orientation W_from_A of every IMU sample (robust 9-axis filter), gyro bias per device";
}

std::vector<StageOption> ImuOrientationStage::options() const {
  const imu::RobustOrientationFilter::Params defaults;
  return {
      {kTauAccKey, format_double(defaults.tau_acc_s),
       "inclination: time constant of the accelerometer low-pass, seconds"},
      {kTauMagKey, format_double(defaults.tau_mag_s),
       "heading: time constant of the magnetometer correction, seconds"},
      {"imu.mag_calibration.<device_id>", "",
       "magnetometer calibration made before the session (paper 1 eq. 3): 'o_x o_y o_z' (uT) and the 3x3 "
       "correction row by row; applied to the device's readings before the filter"},
  };
}

void ImuOrientationStage::start(const v1::SessionHeader& header, StageOutput& /*out*/) {
  imu::RobustOrientationFilter::Params params;
  params.tau_acc_s = time_constant_option(header, kTauAccKey, params.tau_acc_s);
  params.tau_mag_s = time_constant_option(header, kTauMagKey, params.tau_mag_s);
  for (const v1::ImuDevice& device : header.imu_devices()) {
    device_order_.push_back(device.device_id());
    Device state{imu::RobustOrientationFilter(params)};
    const std::string key = mag_calibration_option_key(device.device_id());
    if (const auto it = header.options().find(key); it != header.options().end()) {
      state.mag_calibration = parse_mag_calibration(it->second, "header.options[" + key + "]");
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
  ImuOrientations orientations{block.device_id, block.samples, {}};
  orientations.W_from_A.reserve(block.samples.size());
  for (imu::ImuSample& sample : orientations.samples) {
    if (device.mag_calibration) sample.mag_uT = device.mag_calibration->apply(sample.mag_uT);  // eq. 3
    const imu::Quat W_from_A = geometry::same_hemisphere(device.filter.update(sample), device.last_W_from_A);
    device.last_W_from_A = W_from_A;
    orientations.W_from_A.push_back(W_from_A);
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
    calibration.set_mag_field_ut(device.filter.mag_ref_norm_uT() > 0.0
                                     ? device.filter.mag_ref_norm_uT()
                                     : std::numeric_limits<double>::quiet_NaN());
    *calibration.mutable_gyro_bias_rad_s() = to_proto(device.filter.gyro_bias_rad_s());
  }
}

}  // namespace posefuse::session
