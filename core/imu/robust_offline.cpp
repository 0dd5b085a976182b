#include "imu/robust_offline.hpp"

#include <algorithm>
#include <cmath>

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
  std::vector<Quat> forward(n);
  for (std::size_t i = 0; i < n; ++i) forward[i] = filter.update(samples[i]);

  // Each pass takes its heading reference from the field at its own start: the two differ by a
  // constant turn about the vertical (the field's direction differs a little between where the
  // recording starts and where it ends). The backward pass is turned onto the forward pass's
  // reference (the recording's start, as a causal run has it) by the circular mean of their
  // heading difference; then the average cancels the opposite lags of the two passes in heading
  // as it does in inclination.
  double sin_sum = 0.0, cos_sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Quat D = backward[i] * forward[i].conjugate();
    const double psi = 2.0 * std::atan2(D.z(), D.w());
    sin_sum += std::sin(psi);
    cos_sum += std::cos(psi);
  }
  const Quat forward_from_backward_reference(Eigen::AngleAxisd(-std::atan2(sin_sum, cos_sum), Vec3::UnitZ()));
  std::vector<Quat> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Quat b = geometry::same_hemisphere(forward_from_backward_reference * backward[i], forward[i]);
    out[i] = Quat(forward[i].coeffs() + b.coeffs()).normalized();
  }
  return out;
}

}  // namespace posefuse::imu
