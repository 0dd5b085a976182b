// A forearm orientation's uncertainty and confidence (forearm/orientation_uncertainty.hpp).
#include "forearm/orientation_uncertainty.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace posefuse::forearm {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

// A hold's own spread adds to the 5.6 degrees every accepted hold was measured to give: a steady
// hold barely changes it, one spread beyond 5.3 degrees (u beyond 7.7, the 15-degree 99 % bound)
// is not confident, and a spread that is not a number trusts nothing.
TEST(PoseCalibrationUncertainty, AHoldsSpreadAddsToTheMeasuredFloor) {
  EXPECT_DOUBLE_EQ(pose_calibration_rms_rad(0.0), kPoseCalibrationRmsRad);
  EXPECT_NEAR(pose_calibration_rms_rad(1.5 * kDeg), 5.80 * kDeg, 0.01 * kDeg);
  EXPECT_NEAR(pose_calibration_rms_rad(6.4 * kDeg), 8.50 * kDeg, 0.01 * kDeg);
  EXPECT_GT(confidence_from_rms_rad(pose_calibration_rms_rad(1.5 * kDeg)), 0.65);
  EXPECT_GT(confidence_from_rms_rad(pose_calibration_rms_rad(5.2 * kDeg)), kConfidentAt);
  EXPECT_LT(confidence_from_rms_rad(pose_calibration_rms_rad(5.4 * kDeg)), kConfidentAt);
  EXPECT_LT(confidence_from_rms_rad(pose_calibration_rms_rad(6.4 * kDeg)), 0.45);
  EXPECT_TRUE(std::isnan(pose_calibration_rms_rad(-0.1)));
  EXPECT_TRUE(std::isnan(pose_calibration_rms_rad(std::numeric_limits<double>::quiet_NaN())));
  EXPECT_EQ(confidence_from_rms_rad(pose_calibration_rms_rad(-0.1)), 0.0);
}

// The forearm axis y_F alone: an isotropic orientation error moves one direction by sqrt(2/3) of
// its RMS angle, measured here by turning y by random turns of known RMS.
TEST(ForearmAxisUncertainty, AnIsotropicTurnMovesADirectionBySqrtTwoThirdsOfItsAngle) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  const double sigma_rad = 3.0 * kDeg;  // per axis: the turn's RMS angle is sqrt(3) sigma
  double turn_sq = 0, direction_sq = 0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d rotation_vector(sigma_rad * normal(rng), sigma_rad * normal(rng), sigma_rad * normal(rng));
    const Eigen::AngleAxisd turn(rotation_vector.norm(), rotation_vector.normalized());
    const Eigen::Vector3d y = turn * Eigen::Vector3d::UnitY();
    turn_sq += rotation_vector.squaredNorm();
    direction_sq += std::pow(std::acos(std::clamp(y.y(), -1.0, 1.0)), 2);
  }
  EXPECT_NEAR(std::sqrt(direction_sq / turn_sq), kDirectionRmsOverOrientationRms, 0.003);
}

// A mounting from motion: its axis error and the filter's steady error as a direction's; the roll
// does not enter. Confidence 0.5 where the Rayleigh 99 % bound (2.146 u) reaches 15 degrees.
TEST(ForearmAxisUncertainty, TheAxisConfidenceIgnoresTheRoll) {
  EXPECT_NEAR(forearm_axis_rms_rad(0.0), kDirectionRmsOverOrientationRms * kFilterRmsRad, 1e-15);
  EXPECT_NEAR(forearm_axis_rms_rad(3.0 * kDeg, 4.0 * kDeg / kDirectionRmsOverOrientationRms), 5.0 * kDeg, 1e-12);
  EXPECT_NEAR(direction_confidence_from_rms_rad(15.0 * kDeg / kDirectionBound99OverRms), 0.5, 1e-12);
  EXPECT_GT(direction_confidence_from_rms_rad(forearm_axis_rms_rad(6.5 * kDeg)), kConfidentAt);
  EXPECT_LT(direction_confidence_from_rms_rad(forearm_axis_rms_rad(7.0 * kDeg)), kConfidentAt);
  // A mounting from motion whose roll is the nominal's +-30 deg is never confident as an orientation,
  // while its axis known to 3 deg is.
  EXPECT_LT(confidence_from_rms_rad(orientation_rms_rad(3.0 * kDeg, 30.0 * kDeg)), 0.01);
  EXPECT_GT(direction_confidence_from_rms_rad(forearm_axis_rms_rad(3.0 * kDeg)), 0.8);
  EXPECT_EQ(direction_confidence_from_rms_rad(std::numeric_limits<double>::quiet_NaN()), 0.0);
}

}  // namespace
}  // namespace posefuse::forearm
