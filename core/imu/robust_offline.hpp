#pragma once
// Non-causal ("offline") orientation for a whole recording, built on RobustOrientationFilter.
//
// Sessions are processed whole, so every sample may use the past and the future:
//  1. a forward pass learns the sensor calibration (gyro bias, hard iron);
//  2. a backward pass (time reversed, gyro negated, so the bias flips sign) starts with that
//     calibration, so its start-up (the end of the recording) already has a good bias;
//  3. a second forward pass starts with the calibration the backward pass ended with, i.e. the
//     bias of the recording's first rest phase even before that rest phase has been seen;
//  4. per sample, the inclination is the average of the forward and backward estimates: the
//     inertial-frame accelerometer low-pass lags in opposite time directions in the two passes,
//     so its lag errors cancel (BROAD: inclination RMSE 0.55 deg vs 0.68 causal);
//  5. the heading is the warm-started forward pass's. Averaging the backward heading in made it
//     worse on BROAD (the backward pass alone: heading 2.84 deg vs 1.69 forward; not understood
//     yet: the magnetometer's error during motion does not cancel between the passes, and the
//     gyro appears to lag the other signals by about one sample, which is not time-symmetric).
// Each pass learns its magnetic reference from its own start, like the causal filter.
#include <vector>

#include "imu/robust_orientation_filter.hpp"

namespace posefuse::imu {

// W_from_A for every sample. Validates the stream first (validate_imu_stream).
std::vector<Quat> robust_orientation_offline(const std::vector<ImuSample>& samples,
                                             const RobustOrientationFilter::Params& params = {});

}  // namespace posefuse::imu
