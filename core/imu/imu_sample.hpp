#pragma once
// One 9-axis IMU sample in the sensor's own frame (A for an arm IMU, B for the base IMU).
#include <cstdint>
#include <vector>

#include "geometry/quaternion.hpp"

namespace posefuse::imu {

using geometry::Quat;
using geometry::Vec3;

struct ImuSample {
  std::int64_t t_us = 0;          // device clock, microseconds; strictly increasing within a stream
  Vec3 gyr_rad_s = Vec3::Zero();  // angular rate, rad/s
  Vec3 acc_m_s2 = Vec3::Zero();   // specific force, m/s^2 (reads +g upwards at rest)
  Vec3 mag_uT = Vec3::Zero();     // magnetic flux density, uT; NaN components mean "no reading"
};

// Checks a stream before any filter touches it: finite gyro/acc values and strictly increasing
// timestamps. Throws posefuse::Error (kInvalidArgument) naming the first bad sample and field.
// Magnetometer NaN is allowed (a missing reading); infinities are not.
void validate_imu_stream(const std::vector<ImuSample>& samples, const char* stream_name = "imu");

// The per-sample part of validate_imu_stream (finite gyro/acc, no infinite magnetometer) for
// code that receives samples one at a time; `index` only names the sample in the error.
// Timestamps are the caller's to check against the previous sample.
void validate_imu_sample(const ImuSample& sample, const char* stream_name, std::size_t index);

}  // namespace posefuse::imu
