#include "imu/robust_offline.hpp"

#include <algorithm>

namespace posefuse::imu {

std::vector<Quat> robust_orientation_offline(const std::vector<ImuSample>& samples,
                                             const RobustOrientationFilter::Params& params) {
  validate_imu_stream(samples, "imu");
  const std::size_t n = samples.size();
  RobustOrientationFilter filter(params);
  for (const ImuSample& s : samples) filter.update(s);

  // Backward pass: reversed time, negated rotation rate (the sensor turns the other way).
  std::vector<Quat> backward(n);
  filter.reset_keeping_calibration(/*flip_gyro=*/true);
  const std::int64_t t_end_us = samples.back().t_us;
  for (std::size_t j = 0; j < n; ++j) {
    const std::size_t i = n - 1 - j;
    ImuSample s = samples[i];
    s.t_us = t_end_us - s.t_us;
    // The forward pass integrates the interval (i-1, i] with the rate of sample i; the same
    // interval backwards, (i+1 -> i), must use the rate of sample i+1 or the pass lags a sample.
    s.gyr_rad_s = -samples[std::min(i + 1, n - 1)].gyr_rad_s;
    backward[i] = filter.update(s);
  }

  filter.reset_keeping_calibration(/*flip_gyro=*/true);
  std::vector<Quat> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Quat forward = filter.update(samples[i]);
    const Quat b = geometry::same_hemisphere(backward[i], forward);
    out[i] = Quat(forward.coeffs() + b.coeffs()).normalized();
  }
  return out;
}

}  // namespace posefuse::imu
