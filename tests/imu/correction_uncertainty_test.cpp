// The pieces of RobustOrientationFilter's uncertainty: one sample's error learned from the
// innovations (InnovationScatter) and a correction's variances and gain (CorrectionUncertainty).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "imu/correction_uncertainty.hpp"
#include "imu/innovation_scatter.hpp"

namespace posefuse::imu {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;
constexpr double kDt = 0.01;

TEST(InnovationScatter, WhiteNoiseIsOneIndependentErrorPerSample) {
  InnovationScatter scatter(2.0, 1.0 * kDeg);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 5.0 * kDeg);
  for (int i = 0; i < 6000; ++i) scatter.learn(Eigen::Vector2d(noise(rng), noise(rng)), 0.0, kDt);
  // Two components of 5 degrees each: 50 deg^2 per sample.
  EXPECT_NEAR(std::sqrt(scatter.scatter_rad2()), std::sqrt(50.0) * kDeg, 0.5 * kDeg);
  EXPECT_LT(scatter.correlation_s(kDt), 3.0 * kDt);
  EXPECT_LT(scatter.persistent_rad(), 1.0 * kDeg);
}

TEST(InnovationScatter, AnErrorThatLastsCountsOncePerItsDuration) {
  // A disturbance that holds for a second at a time (an arm's acceleration through a reach).
  InnovationScatter scatter(2.0, 1.0 * kDeg);
  std::mt19937 rng(5);
  std::normal_distribution<double> level(0.0, 5.0 * kDeg);
  double current = 0.0;
  for (int i = 0; i < 20000; ++i) {
    if (i % 100 == 0) current = level(rng);
    scatter.learn(Eigen::Vector2d(current, 0.0), 0.0, kDt);
  }
  EXPECT_GT(scatter.correlation_s(kDt), 0.3);
  EXPECT_GT(scatter.sample_var_rad2(kDt), 30.0 * scatter.scatter_rad2());
}

TEST(InnovationScatter, ABiasShowsAsPersistentAndTheEstimatesOwnVarianceIsNotScatter) {
  InnovationScatter scatter(2.0, 1.0 * kDeg);
  for (int i = 0; i < 2000; ++i) scatter.learn(Eigen::Vector2d(8.0 * kDeg, 0.0), 0.0, kDt);
  EXPECT_NEAR(scatter.persistent_rad(), 8.0 * kDeg, 0.1 * kDeg);
  EXPECT_NEAR(scatter.correlation_s(kDt), 2.0, 1e-9);  // as long as it can tell
  InnovationScatter explained(2.0, 1.0 * kDeg);
  // Innovations no larger than the estimate's own uncertainty: the floor, the sensor's noise.
  for (int i = 0; i < 2000; ++i) explained.learn(Eigen::Vector2d(3.0 * kDeg, 0.0), 16.0 * kDeg * kDeg, kDt);
  EXPECT_NEAR(explained.scatter_rad2(), 1.0 * kDeg * kDeg, 1e-12);
}

TEST(CorrectionUncertainty, AStartUpsAveragingIsExcessOverSteadyTracking) {
  // From an unknown estimate, equal-weight averaging of n samples (min_gain 1/n) leaves one
  // sample's variance over n; steady tracking, following the time constant's small gain from no
  // error, holds far less, so nearly all of it is reported as excess.
  CorrectionUncertainty u;
  const double tau_gain = 0.005, sample_var = 100.0 * kDeg * kDeg;
  for (int n = 1; n <= 80; ++n) {
    EXPECT_DOUBLE_EQ(u.correct(tau_gain, 1.0 / n, sample_var, 0.0, true, Eigen::Vector2d::Zero()), 1.0 / n);
  }
  EXPECT_NEAR(u.reported_var_rad2, sample_var / 80.0, 1e-12);
  EXPECT_LT(u.steady_var_rad2, 0.25 * sample_var / 80.0);
  EXPECT_GT(u.excess_var_rad2(), 0.75 * u.reported_var_rad2);
}

TEST(CorrectionUncertainty, SteadyTrackingHasNoExcessAndTakesTheTimeConstantsGain) {
  CorrectionUncertainty u;
  u.gain_var_rad2 = u.reported_var_rad2 = u.error_var_rad2 = 0.0;
  const double tau_gain = 0.005, sample_var = 4.0 * kDeg * kDeg;
  for (int i = 0; i < 5000; ++i) {
    EXPECT_DOUBLE_EQ(u.correct(tau_gain, 0.0, sample_var, 0.0, true, Eigen::Vector2d::Zero()), tau_gain);
  }
  // The Joseph form's fixed point for a fixed gain: k R / (2 - k).
  EXPECT_NEAR(u.reported_var_rad2, tau_gain * sample_var / (2.0 - tau_gain), 1e-9);
  EXPECT_NEAR(u.excess_var_rad2(), 0.0, 1e-12);
}

TEST(CorrectionUncertainty, AGapRecoversWithKalmanGainsUntilBackToSteady) {
  CorrectionUncertainty u;
  u.gain_var_rad2 = u.reported_var_rad2 = u.error_var_rad2 = u.steady_var_rad2 = 0.0;
  const double tau_gain = 0.005, sample_var = 4.0 * kDeg * kDeg;
  u.add_gap(std::pow(20.0 * kDeg, 2), std::pow(40.0 * kDeg, 2));
  ASSERT_TRUE(u.recovering);
  EXPECT_NEAR(std::sqrt(u.excess_var_rad2()), 40.0 * kDeg, 0.01 * kDeg);
  // The first sample takes nearly all of it: 400 / (400 + 4).
  EXPECT_NEAR(u.correct(tau_gain, 0.0, sample_var, 0.0, true, Eigen::Vector2d(20.0 * kDeg, 0.0)), 400.0 / 404.0, 1e-9);
  int steps = 1;
  while (u.recovering && steps < 100000) {
    u.correct(tau_gain, 0.0, sample_var, 0.0, true, Eigen::Vector2d::Zero());
    ++steps;
  }
  EXPECT_FALSE(u.recovering);
  EXPECT_LT(steps, 2000);
  // Every sample agreed with the corrected estimate: the evidence says it is good.
  EXPECT_LT(std::sqrt(u.excess_var_rad2()), 1.0 * kDeg);
}

TEST(CorrectionUncertainty, AnErrorTheSamplesShowIsReportedUntilItIsCorrected) {
  CorrectionUncertainty u;
  u.gain_var_rad2 = u.reported_var_rad2 = u.error_var_rad2 = u.steady_var_rad2 = 0.0;
  u.add_gap(std::pow(0.1 * kDeg, 2), std::pow(40.0 * kDeg, 2));
  // The bridge looked good, so the gain stays near the time constant's, but the estimate is 30
  // degrees off: every sample shows it (noise-free here) and each correction takes k of it.
  double error = 30.0 * kDeg;
  for (int i = 0; i < 2000; ++i) {
    const double k = u.correct(0.005, 0.0, 4.0 * kDeg * kDeg, 0.0, true, Eigen::Vector2d(error, 0.0));
    error -= k * error;
    const double reported = std::sqrt(u.excess_var_rad2());
    if (i > 10) {
      ASSERT_GT(1.944 * reported, error) << i;  // the 99 % bound holds all along
    }
  }
  EXPECT_LT(error, 3.0 * kDeg);
}

TEST(CorrectionUncertainty, ASharedErrorIsNotAveragedAwayAndIsTakenOnceItShrinks) {
  CorrectionUncertainty u;
  u.gain_var_rad2 = u.reported_var_rad2 = u.error_var_rad2 = u.steady_var_rad2 = 0.0;
  u.add_gap(std::pow(30.0 * kDeg, 2), std::pow(30.0 * kDeg, 2));
  const double shared = std::pow(25.0 * kDeg, 2);
  for (int i = 0; i < 500; ++i) u.correct(0.0005, 0.0, 1.0 * kDeg * kDeg, shared, false, Eigen::Vector2d::Zero());
  EXPECT_GE(u.gain_var_rad2, shared);  // averaging many samples does not remove what they share
  EXPECT_TRUE(u.recovering);           // and the recovery waits (may_end false)
  // Once the shared error is gone, the next sample takes what it left.
  EXPECT_GT(u.correct(0.0005, 0.0, 1.0 * kDeg * kDeg, 0.0, true, Eigen::Vector2d::Zero()), 0.9);
}

}  // namespace
}  // namespace posefuse::imu
