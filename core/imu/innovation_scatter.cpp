#include "imu/innovation_scatter.hpp"

#include <algorithm>

#include "imu/lowpass_gain.hpp"

namespace posefuse::imu {

InnovationScatter::InnovationScatter(double tau_s, double min_sigma_rad)
    : tau_s_(tau_s), min_var_rad2_(min_sigma_rad * min_sigma_rad) {}

void InnovationScatter::learn(const Eigen::Vector2d& innovation_rad, double estimate_var_rad2, double dt_s) {
  const double g = lowpass_gain(dt_s, tau_s_);
  scatter_rad2_ += g * (std::max(0.0, innovation_rad.squaredNorm() - estimate_var_rad2) - scatter_rad2_);
  lowpass_rad_ += g * (innovation_rad - lowpass_rad_);
  lowpass_var_rad2_ += g * (lowpass_rad_.squaredNorm() - lowpass_var_rad2_);
  learned_s_ += dt_s;
  const double g_persistent = learned_s_ > 0.0 ? std::max(g, dt_s / learned_s_) : g;
  persistent_rad_ += g_persistent * (innovation_rad - persistent_rad_);
}

double InnovationScatter::scatter_rad2() const { return std::max(scatter_rad2_, min_var_rad2_); }

double InnovationScatter::correlation_s(double dt_s) const {
  // A first-order low-pass over tau passes dt / (2 tau) of white noise's variance and all of an
  // error that lasts beyond tau: the share it passes gives the error's correlation time.
  return std::clamp(2.0 * tau_s_ * lowpass_var_rad2_ / scatter_rad2(), dt_s, tau_s_);
}

double InnovationScatter::sample_var_rad2(double dt_s, double extra_rad2) const {
  const double var = scatter_rad2() + extra_rad2;
  if (!(dt_s > 0.0)) return var;
  return var * std::max(1.0, correlation_s(dt_s) / dt_s);
}

}  // namespace posefuse::imu
