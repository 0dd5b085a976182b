#include "imu/gyro_bias_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.hpp"

namespace posefuse::imu {

GyroBiasTracker::GyroBiasTracker(const Params& params) : params_(params), bias_rad_s_(params.initial_bias_rad_s) {
  if (!(params.still_threshold_rad_s > 0.0) || !std::isfinite(params.still_threshold_rad_s)) {
    throw_invalid("gyro_bias.still_threshold_rad_s",
                  "must be positive and finite, got " + std::to_string(params.still_threshold_rad_s));
  }
  if (params.window_samples < 1) {
    throw_invalid("gyro_bias.window_samples", "must be >= 1, got " + std::to_string(params.window_samples));
  }
  if (!(params.max_still_rate_rad_s > 0.0)) {
    throw_invalid("gyro_bias.max_still_rate_rad_s",
                  "must be positive (infinity disables it), got " + std::to_string(params.max_still_rate_rad_s));
  }
  if (!params.initial_bias_rad_s.allFinite()) {
    throw_invalid("gyro_bias.initial_bias_rad_s", "not finite");
  }
}

void GyroBiasTracker::reset() {
  bias_rad_s_ = params_.initial_bias_rad_s;
  has_previous_ = false;
  still_count_ = 0;
}

const Vec3& GyroBiasTracker::update(const Vec3& rate) {
  const bool comparable = has_previous_;
  const Vec3 change = rate - previous_rate_rad_s_;
  previous_rate_rad_s_ = rate;
  has_previous_ = true;
  if (!comparable) return bias_rad_s_;

  // Paper II-E-2: all three axes within the threshold of the previous sample.
  const bool still = change.cwiseAbs().maxCoeff() < params_.still_threshold_rad_s &&
                     (rate - bias_rad_s_).cwiseAbs().maxCoeff() < params_.max_still_rate_rad_s;
  if (!still) return bias_rad_s_;

  ++still_count_;
  const double weight = 1.0 / static_cast<double>(std::min<std::int64_t>(still_count_, params_.window_samples));
  bias_rad_s_ += weight * (rate - bias_rad_s_);
  return bias_rad_s_;
}

}  // namespace posefuse::imu
