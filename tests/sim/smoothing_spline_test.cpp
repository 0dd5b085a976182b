// The noise-chosen smoothing spline (smoothing_spline.hpp): its noise estimate, its limits
// (lambda 0: the data; lambda large: the least-squares line) and the acceleration of an analytic
// motion sampled like mocap (60 Hz, 1 mm of jitter) recovered from it.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "common/error.hpp"
#include "sim/sensor_trajectory.hpp"
#include "sim/smoothing_spline.hpp"
#include "sim/uniform_cubic_spline.hpp"

using namespace posefuse;
using namespace posefuse::sim;
using std::numbers::pi;

namespace {

constexpr double kH = 1.0 / 60;

// An arm-like motion: three sinusoids of 0.5-1.1 Hz, up to 0.3 m; accelerations up to ~9 m/s^2.
Vec3 position(double t) {
  return {0.3 * std::sin(2 * pi * 0.5 * t), 0.2 * std::sin(2 * pi * 0.8 * t + 1.0), 0.1 * std::cos(2 * pi * 1.1 * t)};
}
Vec3 acceleration(double t) {
  const double w1 = 2 * pi * 0.5, w2 = 2 * pi * 0.8, w3 = 2 * pi * 1.1;
  return {-0.3 * w1 * w1 * std::sin(w1 * t), -0.2 * w2 * w2 * std::sin(w2 * t + 1.0),
          -0.1 * w3 * w3 * std::cos(w3 * t)};
}

std::vector<Eigen::VectorXd> mocap_samples(int n, double sigma_m, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma_m);
  std::vector<Eigen::VectorXd> out;
  for (int k = 0; k < n; ++k) {
    Eigen::VectorXd v = position(k * kH);
    for (int i = 0; i < 3; ++i) v[i] += noise(rng);
    out.push_back(v);
  }
  return out;
}

// RMS of |a - analytic| over [1, T - 1] s from a natural spline through `frames`, sampled at
// 1 kHz and differentiated by SensorKinematics (as the simulator does).
double acceleration_rms_error(const std::vector<Eigen::VectorXd>& frames) {
  const UniformCubicSpline spline(0.0, kH, frames);
  SensorTrajectory trajectory;
  trajectory.dt_s = 1e-3;
  for (double t = 0; t <= spline.t_end_s(); t += 1e-3) {
    trajectory.p_W_m.push_back(spline.at(t).head<3>());
    trajectory.W_from_A.push_back(Quat::Identity());
  }
  const SensorKinematics kinematics(std::move(trajectory));
  double sum = 0;
  int count = 0;
  for (double t = 1.0; t <= spline.t_end_s() - 1.0; t += 0.0125) {
    sum += (kinematics.at(t).a_W_m_s2 - acceleration(t)).squaredNorm();
    ++count;
  }
  return std::sqrt(sum / count);
}

}  // namespace

TEST(SmoothingSpline, NoiseEstimateOfJitterOnAMotion) {
  for (const double sigma : {0.0005, 0.001, 0.003}) {
    const auto frames = mocap_samples(1200, sigma, 3);
    Eigen::VectorXd x(1200);
    for (int k = 0; k < 1200; ++k) x[k] = frames[static_cast<std::size_t>(k)][0];
    const double estimate = noise_sigma_from_differences(x);
    std::printf("sigma %.4f m: estimated %.5f m\n", sigma, estimate);
    // The median of 1196 correlated |fourth differences|: a few per cent of spread; 10 % allowed.
    EXPECT_NEAR(estimate, sigma, 0.1 * sigma);
  }
}

TEST(SmoothingSpline, LambdaZeroIsTheDataLargeLambdaTheLeastSquaresLine) {
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.01);
  Eigen::VectorXd y(200), t(200);
  for (int k = 0; k < 200; ++k) {
    t[k] = k * kH;
    y[k] = 0.5 - 2.0 * t[k] + noise(rng);
  }
  EXPECT_EQ(smoothing_spline_values(y, kH, 0.0), y);
  Eigen::MatrixXd A(200, 2);
  A.col(0).setOnes();
  A.col(1) = t;
  const Eigen::VectorXd line = A * A.colPivHouseholderQr().solve(y);
  const Eigen::VectorXd f = smoothing_spline_values(y, kH, 1e9);
  EXPECT_LT((f - line).cwiseAbs().maxCoeff(), 1e-5);
}

TEST(SmoothingSpline, ChosenSmoothingLeavesTheNoiseAsResidual) {
  const auto frames = mocap_samples(1200, 0.001, 7);
  Eigen::VectorXd y(1200), truth(1200);
  for (int k = 0; k < 1200; ++k) {
    y[k] = frames[static_cast<std::size_t>(k)][1];
    truth[k] = position(k * kH)[1];
  }
  const NoiseChosenSmoothing s = smooth_by_noise_level(y, kH);
  const double residual_rms = std::sqrt((y - s.values).squaredNorm() / 1200);
  const double error_rms = std::sqrt((s.values - truth).squaredNorm() / 1200);
  std::printf("noise %.5f, residual %.5f, error to the truth %.5f m, lambda %.3g\n", s.noise_sigma, residual_rms,
              error_rms, s.lambda);
  EXPECT_NEAR(residual_rms, s.noise_sigma, 1e-3 * s.noise_sigma);  // Reinsch's criterion, bisected
  EXPECT_LT(error_rms, s.noise_sigma);                             // closer to the motion than the samples are
}

// The specific force's motion part: the analytic acceleration vs what the simulator's chain
// (60 Hz samples, smoothing, natural spline, 1 kHz, 5-point second difference) recovers.
TEST(SmoothingSpline, AccelerationOfAnAnalyticMotionFromJitteredMocap) {
  const auto noisy = mocap_samples(1200, 0.001, 11);  // 20 s
  const double raw = acceleration_rms_error(noisy);
  const double gaussian = acceleration_rms_error(gaussian_smooth(noisy, 0.03 / kH));
  const double spline = acceleration_rms_error(smooth_by_noise_level(noisy, kH));
  const double clean = acceleration_rms_error(mocap_samples(1200, 0.0, 11));
  std::printf(
      "rms |a| error, m/s^2: clean samples %.4f, jittered unsmoothed %.3f, Gaussian 0.03 s %.3f, "
      "noise-chosen spline %.3f\n",
      clean, raw, gaussian, spline);
  // The chain itself: a cubic spline's second derivative is off by at most 3/8 h^2 |p^(4)|
  // (Hall and Meyer 1976), |p^(4)| <= 0.3 w1^4 + 0.2 w2^4 + 0.1 w3^4 = 385 m/s^4: 0.040 m/s^2.
  const double w1 = 2 * pi * 0.5, w2 = 2 * pi * 0.8, w3 = 2 * pi * 1.1;
  EXPECT_LT(clean, 3.0 / 8.0 * kH * kH * (0.3 * std::pow(w1, 4) + 0.2 * std::pow(w2, 4) + 0.1 * std::pow(w3, 4)));
  EXPECT_GT(raw, 10.0);  // 1 mm of jitter twice differentiated at 60 Hz
  EXPECT_LT(spline, gaussian);
}

TEST(SmoothingSpline, RejectsBadInput) {
  Eigen::VectorXd y = Eigen::VectorXd::Zero(10);
  EXPECT_THROW(smooth_by_noise_level(y, 0.0), Error);
  y[3] = std::nan("");
  EXPECT_THROW(smooth_by_noise_level(y, kH), Error);
  EXPECT_THROW(smoothing_spline_values(Eigen::VectorXd::Zero(10), kH, -1.0), Error);
}
