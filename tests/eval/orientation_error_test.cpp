#include "eval/orientation_error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "common/error.hpp"

using posefuse::eval::orientation_error;
using posefuse::eval::orientation_rmse;
using posefuse::geometry::Quat;
using posefuse::geometry::Vec3;

namespace {
constexpr double kDeg = EIGEN_PI / 180.0;
Quat rot(double angle_rad, const Vec3& axis) { return Quat(Eigen::AngleAxisd(angle_rad, axis.normalized())); }
// An arbitrary tilted ground truth, so the tests do not only pass for identity.
Quat some_gt() { return rot(1.1, Vec3(0.3, -0.5, 0.8)); }
}  // namespace

TEST(OrientationError, PureHeadingError) {
  const Quat gt = some_gt();
  const Quat est = rot(10 * kDeg, Vec3::UnitZ()) * gt;  // q_err = est * gt^-1 = Rz(10 deg)
  const auto e = orientation_error(est, gt);
  EXPECT_NEAR(e.heading_rad, 10 * kDeg, 1e-9);
  EXPECT_NEAR(e.inclination_rad, 0.0, 1e-7);
  EXPECT_NEAR(e.total_rad, 10 * kDeg, 1e-9);
}

TEST(OrientationError, PureTiltError) {
  const Quat gt = some_gt();
  const Quat est = rot(7 * kDeg, Vec3(1, 2, 0)) * gt;  // any horizontal axis
  const auto e = orientation_error(est, gt);
  EXPECT_NEAR(e.heading_rad, 0.0, 1e-9);
  EXPECT_NEAR(e.inclination_rad, 7 * kDeg, 1e-9);
  EXPECT_NEAR(e.total_rad, 7 * kDeg, 1e-9);
}

TEST(OrientationError, MixedErrorSplitsIntoHeadingThenTilt) {
  // q_err = Rz(a) * Rx(b): w = cos(a/2)cos(b/2), z = sin(a/2)cos(b/2), so
  // heading = a, inclination = b and total = 2 acos(cos(a/2) cos(b/2)).
  const double a = 20 * kDeg, b = 5 * kDeg;
  const Quat gt = some_gt();
  const Quat est = rot(a, Vec3::UnitZ()) * rot(b, Vec3::UnitX()) * gt;
  const auto e = orientation_error(est, gt);
  EXPECT_NEAR(e.heading_rad, a, 1e-9);
  EXPECT_NEAR(e.inclination_rad, b, 1e-9);
  EXPECT_NEAR(e.total_rad, 2 * std::acos(std::cos(a / 2) * std::cos(b / 2)), 1e-9);
}

TEST(OrientationError, SignOfQuaternionDoesNotMatter) {
  const Quat gt = some_gt();
  const Quat est = rot(30 * kDeg, Vec3(0.2, 0.1, 1.0)) * gt;
  const Quat neg_est(-est.w(), -est.x(), -est.y(), -est.z());
  const auto e1 = orientation_error(est, gt);
  const auto e2 = orientation_error(neg_est, gt);
  EXPECT_NEAR(e1.total_rad, e2.total_rad, 1e-12);
  EXPECT_NEAR(e1.heading_rad, e2.heading_rad, 1e-12);
  EXPECT_NEAR(e1.inclination_rad, e2.inclination_rad, 1e-12);
  EXPECT_NEAR(e1.total_rad, 30 * kDeg, 1e-9);
}

TEST(OrientationRmse, UsesOnlyCountedFiniteSamples) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Quat gt = some_gt();
  std::vector<Quat> est = {rot(3 * kDeg, Vec3::UnitZ()) * gt, rot(4 * kDeg, Vec3::UnitZ()) * gt,
                           rot(50 * kDeg, Vec3::UnitZ()) * gt, rot(90 * kDeg, Vec3::UnitX()) * gt};
  std::vector<Quat> truth = {gt, gt, gt, Quat(nan, nan, nan, nan)};
  std::vector<bool> counted = {true, true, false, true};
  const auto r = orientation_rmse(est, truth, counted);
  EXPECT_EQ(r.samples, 2u);
  EXPECT_NEAR(r.heading_rad, std::sqrt((9.0 + 16.0) / 2.0) * kDeg, 1e-9);
  EXPECT_NEAR(r.total_rad, r.heading_rad, 1e-9);
  EXPECT_NEAR(r.inclination_rad, 0.0, 1e-7);
}

TEST(OrientationRmse, RejectsSizeMismatch) {
  EXPECT_THROW(orientation_rmse({Quat::Identity()}, {}, {}), posefuse::Error);
  EXPECT_THROW(orientation_rmse({Quat::Identity()}, {Quat::Identity()}, {}), posefuse::Error);
}

TEST(OrientationRmse, NoCountedSampleGivesNaN) {
  const auto r = orientation_rmse({Quat::Identity()}, {Quat::Identity()}, {false});
  EXPECT_EQ(r.samples, 0u);
  EXPECT_TRUE(std::isnan(r.total_rad));
}
