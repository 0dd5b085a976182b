// The calibration pose tests (paper 1, Fig. 3b: forearm raised, upper arm not raised overhead,
// elbow flexed), the first two against a tilted camera's up.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "forearm/calibration_pose_check.hpp"
#include "geometry/quaternion.hpp"

namespace posefuse::forearm {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

TEST(CalibrationPoseCheck, RaisedForearmPassesAndRestingArmFails) {
  // A camera pitched down by 20 degrees: up in K is not K's y.
  const Vec3 up_K = geometry::quat_from_rotation_vector(Vec3(20 * kDeg, 0, 0)) * Vec3::UnitY();
  const Vec3 elbow(0.3, 0.2, 2.0);
  const auto forearm_at = [&](double tilt_deg) -> Vec3 {
    // Tilted from up about the horizontal axis x_K (K is pitched about x only).
    return elbow + 0.25 * (geometry::quat_from_rotation_vector(Vec3(tilt_deg * kDeg, 0, 0)) * up_K);
  };
  EXPECT_TRUE(forearm_raised_for_calibration(elbow, forearm_at(0), up_K));
  EXPECT_TRUE(forearm_raised_for_calibration(elbow, forearm_at(44), up_K));
  EXPECT_FALSE(forearm_raised_for_calibration(elbow, forearm_at(46), up_K));
  EXPECT_FALSE(forearm_raised_for_calibration(elbow, forearm_at(180), up_K));  // hanging
  EXPECT_FALSE(forearm_raised_for_calibration(elbow, elbow, up_K));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(forearm_raised_for_calibration(elbow, Vec3(nan, 0, 0), up_K));
}

TEST(CalibrationPoseCheck, UpperArmToTheSideOrDownPassesAndOverheadFails) {
  const Vec3 up_K = geometry::quat_from_rotation_vector(Vec3(20 * kDeg, 0, 0)) * Vec3::UnitY();
  const Vec3 shoulder(0.3, 0.4, 2.0);
  const auto elbow_at = [&](double rise_deg) -> Vec3 {
    // Abducted in K's x-up plane: 0 = horizontal to the side, 90 = straight up, -90 = hanging.
    const Vec3 side = Vec3::UnitX();
    return shoulder + 0.3 * (std::cos(rise_deg * kDeg) * side + std::sin(rise_deg * kDeg) * up_K);
  };
  EXPECT_TRUE(upper_arm_lowered_for_calibration(shoulder, elbow_at(0), up_K));    // paper 1's pose
  EXPECT_TRUE(upper_arm_lowered_for_calibration(shoulder, elbow_at(-90), up_K));  // hanging, forearm up
  EXPECT_TRUE(upper_arm_lowered_for_calibration(shoulder, elbow_at(44), up_K));
  EXPECT_FALSE(upper_arm_lowered_for_calibration(shoulder, elbow_at(46), up_K));
  EXPECT_FALSE(upper_arm_lowered_for_calibration(shoulder, elbow_at(75), up_K));  // arm raising's top
  EXPECT_FALSE(upper_arm_lowered_for_calibration(shoulder, shoulder, up_K));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(upper_arm_lowered_for_calibration(Vec3(nan, 0, 0), elbow_at(0), up_K));
}

TEST(CalibrationPoseCheck, FlexedElbowPassesAndStraightArmFails) {
  const Vec3 shoulder(0.3, 0.4, 2.0), elbow(0.6, 0.4, 2.0);  // the upper arm along +x
  const auto wrist_at = [&](double flexion_deg) -> Vec3 {
    return elbow + 0.25 * Vec3(std::cos(flexion_deg * kDeg), std::sin(flexion_deg * kDeg), 0.0);
  };
  EXPECT_TRUE(elbow_flexed_for_calibration(shoulder, elbow, wrist_at(90)));  // paper 1's pose
  EXPECT_TRUE(elbow_flexed_for_calibration(shoulder, elbow, wrist_at(46)));
  EXPECT_TRUE(elbow_flexed_for_calibration(shoulder, elbow, wrist_at(150)));
  EXPECT_FALSE(elbow_flexed_for_calibration(shoulder, elbow, wrist_at(44)));
  EXPECT_FALSE(elbow_flexed_for_calibration(shoulder, elbow, wrist_at(0)));  // straight
  EXPECT_FALSE(elbow_flexed_for_calibration(shoulder, elbow, elbow));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(elbow_flexed_for_calibration(shoulder, elbow, Vec3(nan, 0, 0)));
}

}  // namespace
}  // namespace posefuse::forearm
