// The calibration pose test (paper 1, Fig. 3b: forearm raised) against a tilted camera's up.
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

}  // namespace
}  // namespace posefuse::forearm
