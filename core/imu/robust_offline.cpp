#include "imu/robust_offline.hpp"

#include <algorithm>
#include <cmath>

namespace posefuse::imu {

namespace {

// `tilt_source` turned about the vertical so that it differs from `heading_source` by a pure
// tilt: with D = tilt_source * heading_source^-1 = (w, x, y, z), Rz(psi) * D has no z part for
// psi = -2 atan2(z, w), so heading (as the BROAD metric splits it) comes from heading_source and
// inclination from tilt_source.
Quat with_heading_of(const Quat& tilt_source, const Quat& heading_source) {
  const Quat D = tilt_source * heading_source.conjugate();
  const double psi = -2.0 * std::atan2(D.z(), D.w());
  return Quat(Eigen::AngleAxisd(psi, Vec3::UnitZ())) * tilt_source;
}

}  // namespace

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
    const Quat averaged = Quat(forward.coeffs() + b.coeffs()).normalized();
    out[i] = with_heading_of(averaged, forward);
  }
  return out;
}

}  // namespace posefuse::imu
