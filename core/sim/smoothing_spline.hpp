#pragma once
// Cubic smoothing spline with its smoothing chosen from the data's own noise level, for mocap
// at its recorded rate: the specific force an IMU reads is the second derivative of positions
// that optical mocap gives with millimetres of jitter, so a fixed smoothing either leaves noise
// (fast rates) or flattens real motion (slow rates).
//
// Per channel y_0..y_{n-1} on a uniform grid h, the spline f minimises
//   sum_k (y_k - f(t_k))^2 + lambda * integral f''(t)^2 dt,
// a natural cubic spline with knots at the samples (Reinsch 1967): with Q the n x (n-2) second
// difference matrix (1, -2, 1) / h and R the (n-2) x (n-2) tridiagonal (h/6, 2h/3, h/6),
//   (R + lambda Q^T Q) gamma = Q^T y,   f = y - lambda Q gamma,
// gamma being f'' at the inner knots. The natural cubic spline through f (uniform_cubic_spline.hpp)
// is then exactly the smoothing spline.
// Noise level: white noise of standard deviation sigma gives fourth differences of variance
// 70 sigma^2, while a motion sampled at 60 Hz contributes h^4 |y''''| (4e-6 of the amplitude at
// 2 Hz), so sigma = 1.4826 median|diff4 y| / sqrt(70) (the median keeps a few fast moments out).
// Smoothing: Reinsch's criterion, lambda such that sum_k (y_k - f_k)^2 = n sigma^2, found by
// bisection on log lambda (the residual grows monotonically with lambda).
#include <vector>

#include <Eigen/Core>

namespace posefuse::sim {

// Robust noise standard deviation of one equally spaced channel from its fourth differences;
// 0 for fewer than 5 samples.
double noise_sigma_from_differences(const Eigen::VectorXd& y);

// The smoothing spline's values at the knots for a given lambda (>= 0, s^3 in the units of y^2).
Eigen::VectorXd smoothing_spline_values(const Eigen::VectorXd& y, double h_s, double lambda);

struct NoiseChosenSmoothing {
  Eigen::VectorXd values;  // the smoothing spline at the knots
  double noise_sigma = 0;  // estimated
  double lambda = 0;       // chosen
};

// Reinsch's criterion with the estimated noise. kInvalidArgument for h_s not > 0 or non-finite y.
NoiseChosenSmoothing smooth_by_noise_level(const Eigen::VectorXd& y, double h_s);

// Every component of equally spaced vectors, each smoothed by its own noise level.
std::vector<Eigen::VectorXd> smooth_by_noise_level(const std::vector<Eigen::VectorXd>& frames, double h_s);

}  // namespace posefuse::sim
