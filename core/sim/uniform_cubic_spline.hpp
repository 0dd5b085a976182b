#pragma once
// Natural cubic spline through vector values on a uniform grid: C2-smooth, passes through
// every value, second derivative zero at both ends. Used to turn 60-120 Hz motion capture into
// the dense, smooth poses that IMU synthesis differentiates (slerp between frames would give
// piecewise-constant rates and impulsive accelerations).
#include <Eigen/Core>
#include <vector>

namespace posefuse::sim {

class UniformCubicSpline {
 public:
  // values[k] at t0 + k * dt. kInvalidArgument for fewer than 2 values, differing sizes,
  // non-finite values or dt not > 0.
  UniformCubicSpline(double t0_s, double dt_s, std::vector<Eigen::VectorXd> values);

  double t_begin_s() const { return t0_s_; }
  double t_end_s() const { return t0_s_ + dt_s_ * static_cast<double>(values_.size() - 1); }

  // Clamped to [t_begin_s, t_end_s].
  Eigen::VectorXd at(double t_s) const;
  // Outside [t_begin_s, t_end_s] continued along the end tangent; because the second derivative
  // is zero at the ends, the continuation is still C2 (used where a few samples beyond the ends
  // are differentiated).
  Eigen::VectorXd at_extended(double t_s) const;

 private:
  double t0_s_;
  double dt_s_;
  std::vector<Eigen::VectorXd> values_;
  std::vector<Eigen::VectorXd> second_derivatives_;
};

// Zero-phase Gaussian smoothing of a sequence of equally spaced vectors, standard deviation
// sigma_frames (in samples; <= 0 returns the input); the kernel is cut at 3 sigma; beyond the
// ends the sequence is continued by point reflection about the end values (a linear trend
// stays linear, so a steady motion is not bent near the ends).
std::vector<Eigen::VectorXd> gaussian_smooth(const std::vector<Eigen::VectorXd>& frames, double sigma_frames);

}  // namespace posefuse::sim
