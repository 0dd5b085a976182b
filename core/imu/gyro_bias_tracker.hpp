#pragma once
// Gyroscope bias tracking of paper 1, II-E-2.
//
// Two consecutive gyro samples are compared; when all three axes differ by less than
// `still_threshold_rad_s` (paper: 3 deg/s, "a measured range of static random noise") the
// sensor is taken as still and the newer sample enters a running average that is the bias.
//
// Averaging: the k-th accepted sample gets weight 1/min(k, window_samples). Until
// `window_samples` still samples have been seen this is the exact mean of all of them (so the
// estimate is usable after the first still moment and has no start-up bias towards zero); after
// that it is an exponential forgetting average with factor 1 - 1/window_samples, i.e. a memory of
// about `window_samples` still samples. Default 800 = 10 s of stillness at 80 Hz: white gyro
// noise of sigma averages down by sqrt(800) ~ 28x, while bias drift with temperature (minutes)
// is still followed. The paper says only "the average bias will change slowly".
//
// Known limit of the paper's test (kept because it is the paper's method): it looks at the
// change of the rate, not the rate, so a rotation at a nearly constant rate (or the turning
// points of a swing) also counts as still and pulls the bias towards the true rate. Setting
// `max_still_rate_rad_s` additionally requires |rate - bias| < that value on every axis; its
// default (infinity) keeps the paper's behaviour.
#include <cstdint>
#include <limits>

#include "geometry/quaternion.hpp"

namespace posefuse::imu {

using geometry::Vec3;

class GyroBiasTracker {
 public:
  struct Params {
    double still_threshold_rad_s = 3.0 * 3.14159265358979323846 / 180.0;  // paper: 3 deg/s
    int window_samples = 800;  // memory of the average, in still samples (>= 1)
    double max_still_rate_rad_s = std::numeric_limits<double>::infinity();  // off = paper
    // E.g. the factory or last session's bias; used until the first still sample, whose value
    // then replaces it (the running mean starts there).
    Vec3 initial_bias_rad_s = Vec3::Zero();
  };

  GyroBiasTracker() : GyroBiasTracker(Params{}) {}
  // Throws posefuse::Error (kInvalidArgument) on non-positive / non-finite parameters.
  explicit GyroBiasTracker(const Params& params);

  // Feeds one raw gyro sample (rad/s, finite) and returns the bias after it.
  const Vec3& update(const Vec3& raw_rate_rad_s);

  const Vec3& bias_rad_s() const { return bias_rad_s_; }
  // Number of samples that have entered the average so far.
  std::int64_t still_sample_count() const { return still_count_; }
  void reset();

 private:
  Params params_;
  Vec3 bias_rad_s_;
  Vec3 previous_rate_rad_s_ = Vec3::Zero();
  bool has_previous_ = false;
  std::int64_t still_count_ = 0;
};

}  // namespace posefuse::imu
