#pragma once
// Non-causal ("offline") orientation for a whole recording, built on RobustOrientationFilter.
//
// Sessions are processed whole, so every sample may use the past and the future:
//  1. a forward pass learns the calibration (gyro bias, magnetic reference, hard iron);
//  2. a backward pass (time reversed, gyro negated) starts with that calibration, so the start
//     of the recording is no longer an unconverged start-up;
//  3. a second forward pass starts with the calibration the backward pass ended with;
//  4. per sample, the forward and backward estimates are averaged. Their errors come from
//     different sides (the past and the future of the sample), so they partly cancel; near a
//     magnetic disturbance one of them has just seen an undisturbed field.
#include <vector>

#include "imu/robust_orientation_filter.hpp"

namespace posefuse::imu {

// W_from_A for every sample. Validates the stream first (validate_imu_stream).
std::vector<Quat> robust_orientation_offline(const std::vector<ImuSample>& samples,
                                             const RobustOrientationFilter::Params& params = {});

}  // namespace posefuse::imu
