#pragma once
// What one sample of a correction (the accelerometer's vertical, the magnetometer's heading)
// tells about the orientation, learned from the innovations while the filter tracks: how far a
// sample scatters beyond the estimate's own uncertainty, and how long its error stays alike.
// A sample's error variance for a Kalman gain is the scatter times the samples per correlation
// time: an arm's accelerations or a pose-dependent field error that last a second are not
// averaged away by a second's samples.
#include <Eigen/Core>

namespace posefuse::imu {

class InnovationScatter {
 public:
  // `tau_s`: time constant of the learning, also the longest correlation time it can tell;
  // `min_sigma_rad`: the sensor's noise, below which no sample's error is taken.
  InnovationScatter(double tau_s, double min_sigma_rad);

  // One sample's innovation (rad; 2-D: the tilt's two horizontal components, or the heading and
  // 0) and the estimate's variance before it (rad^2), dt_s after the previous one.
  void learn(const Eigen::Vector2d& innovation_rad, double estimate_var_rad2, double dt_s);

  double scatter_rad2() const;              // per sample, at least min_sigma_rad^2
  double correlation_s(double dt_s) const;  // between dt_s (white) and tau_s
  // (scatter + extra) * max(1, correlation / dt); `extra_rad2`: an error this sample is known
  // to carry beyond the learned scatter, lasting as long.
  double sample_var_rad2(double dt_s, double extra_rad2 = 0.0) const;
  // The innovation low-passed over tau_s: an error the corrections keep showing (white noise
  // averages out of it). Its first samples are averaged with equal weights, so an error the
  // corrections show from the start (one a start-up's agreeing samples left) shows at once,
  // not over tau_s from zero.
  double persistent_rad() const { return persistent_rad_.norm(); }

 private:
  double tau_s_;
  double min_var_rad2_;
  double scatter_rad2_ = 0.0;
  // The innovation low-passed over tau_s from zero, and its mean square: correlation_s relies on
  // a first-order low-pass passing dt / (2 tau) of white noise, which an equal-weight start would
  // not. The reported persistent error is a second low-pass that averages from the first sample.
  Eigen::Vector2d lowpass_rad_ = Eigen::Vector2d::Zero();
  double lowpass_var_rad2_ = 0.0;
  Eigen::Vector2d persistent_rad_ = Eigen::Vector2d::Zero();
  double learned_s_ = 0.0;  // time learned so far
};

}  // namespace posefuse::imu
