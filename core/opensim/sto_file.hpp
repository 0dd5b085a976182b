#pragma once
// OpenSense orientation file (.sto) of a session's IMU orientations (docs/exports.md, "IMU
// orientations"): DataType=Quaternion, one column per IMU, each cell "w,x,y,z" of the sensor's
// orientation in the ground frame G_from_A, time in seconds on the camera clock.
#include <cstddef>
#include <ostream>
#include <string>

#include "opensim/ground_frame.hpp"

namespace posefuse::opensim {

struct StoSummary {
  std::size_t rows = 0;
  std::size_t imus = 0;
  double rate_hz = 0.0;
  bool camera_ground = false;  // false: the world turned y up (no K_from_W), heading north
  bool camera_clock = false;   // false: some IMU had no clock offset, all stay on the device clock
};

// Columns are named for OpenSense: an arm IMU the calibration report assigns to an arm is
// radius_r_imu / radius_l_imu, any other its device id. Rows are the times of the IMU with the
// most samples within the span all IMUs cover; the others are interpolated (slerp) to them.
// Throws posefuse::Error (kFailedPrecondition) "imu_orientations" without orientations or
// without a common span.
StoSummary write_sto(const session::ResultDirectory& results, const GroundFrame& ground, std::ostream& out);

}  // namespace posefuse::opensim
