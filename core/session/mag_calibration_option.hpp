#pragma once
// A magnetometer calibration made before the session (paper 1, II-E-1: the IMU turned in all
// directions, an ellipsoid fit, eq. 3) carried in the session header's options, one key per
// device:
//   imu.mag_calibration.<device_id> = "o_x o_y o_z c00 c01 c02 c10 c11 c12 c20 c21 c22"
// o the hard-iron centre in uT, c the 3x3 correction row by row (imu::MagCalibration: a reading
// m' is corrected to c (m' - o)). The IMU orientation stage applies it to every sample before
// the filter; the simulator writes it from its own simulated calibration rotation.
#include <string>

#include "imu/mag_calibration.hpp"

namespace posefuse::session {

std::string mag_calibration_option_key(const std::string& device_id);
std::string format_mag_calibration(const imu::MagCalibration& calibration);
// kInvalidArgument naming `field` unless there are 12 finite numbers and c is invertible.
imu::MagCalibration parse_mag_calibration(const std::string& text, const std::string& field);

}  // namespace posefuse::session
