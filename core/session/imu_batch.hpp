#pragma once
// ImuBatch (packed arrays, float) <-> imu::ImuSample (one struct per sample, double).
#include <string>
#include <vector>

#include "imu/imu_sample.hpp"
#include "posefuse/v1/session.pb.h"

namespace posefuse::session {

// Checks the array sizes (t_us n, each vector 3n, n >= 1) and converts; values are not
// checked here (imu::validate_imu_stream does that). Throws kInvalidArgument naming
// `field` + ".gyr_rad_s" etc.
std::vector<imu::ImuSample> samples_from_batch(const v1::ImuBatch& batch, const std::string& field = "imu");

// Values are narrowed to float, as the wire format stores them.
v1::ImuBatch batch_from_samples(const std::string& device_id, const std::vector<imu::ImuSample>& samples);

}  // namespace posefuse::session
