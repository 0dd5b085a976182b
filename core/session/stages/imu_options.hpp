#pragma once
// The IMU orientation stage's SessionHeader.options: their table and what they hold.
#include <map>
#include <string>

#include "imu/mag_calibration.hpp"
#include "imu/robust_orientation_filter.hpp"
#include "posefuse/v1/session.pb.h"
#include "session/option_table.hpp"

namespace posefuse::session {

inline constexpr const char* kImuTauAccKey = "imu.tau_acc_s";
inline constexpr const char* kImuTauMagKey = "imu.tau_mag_s";
// One key per device, mag_calibration_option_key(device_id) (mag_calibration_option.hpp).
inline constexpr const char* kImuMagCalibrationKeys = "imu.mag_calibration.<device_id>";

struct ImuOptions {
  imu::RobustOrientationFilter::Params filter;  // tau_acc_s and tau_mag_s from the options
  // By device id, for the header's devices that have one (paper 1 eq. 3).
  std::map<std::string, imu::MagCalibration> mag_calibrations;
};

const OptionTable& imu_option_table();
// Throws posefuse::Error naming the option for a bad value.
ImuOptions read_imu_options(const v1::SessionHeader& header);

}  // namespace posefuse::session
