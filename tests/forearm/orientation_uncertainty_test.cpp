// A forearm orientation's uncertainty and confidence (forearm/orientation_uncertainty.hpp).
#include "forearm/orientation_uncertainty.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

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

}  // namespace
}  // namespace posefuse::forearm
