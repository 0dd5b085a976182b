#include "imu/robust_offline.hpp"

namespace posefuse::imu {

std::vector<Quat> robust_orientation_offline(const std::vector<ImuSample>& samples,
                                             const RobustOrientationFilter::Params& params) {
  validate_imu_stream(samples, "imu");
  const std::size_t n = samples.size();
  RobustOrientationFilter filter(params);
  for (const ImuSample& s : samples) filter.update(s);

  // Backward pass: reversed time, negated rotation rate (the sensor turns the other way).
  std::vector<Quat> backward(n);
  filter.reset_keeping_calibration();
  const std::int64_t t_end_us = samples.back().t_us;
  for (std::size_t j = 0; j < n; ++j) {
    ImuSample s = samples[n - 1 - j];
    s.t_us = t_end_us - s.t_us;
    s.gyr_rad_s = -s.gyr_rad_s;
    backward[n - 1 - j] = filter.update(s);
  }

  filter.reset_keeping_calibration();
  std::vector<Quat> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Quat forward = filter.update(samples[i]);
    const Quat b = geometry::same_hemisphere(backward[i], forward);
    out[i] = Quat(forward.coeffs() + b.coeffs()).normalized();
  }
  return out;
}

}  // namespace posefuse::imu
