#include "geometry/quaternion.hpp"
#include "geometry/frames.hpp"

#include <gtest/gtest.h>

namespace pg = posefuse::geometry;

TEST(Quaternion, RotationVectorRoundTrip) {
  for (const pg::Vec3& rv : {pg::Vec3(0.3, -0.2, 1.1), pg::Vec3(1e-9, 0, 0), pg::Vec3(0, 3.1, 0)}) {
    const pg::Quat q = pg::quat_from_rotation_vector(rv);
    EXPECT_NEAR(q.norm(), 1.0, 1e-12);
    EXPECT_TRUE(pg::rotation_vector_from_quat(q).isApprox(rv, 1e-9)) << rv.transpose();
  }
}

TEST(Quaternion, RotationVectorMatchesEigenAngleAxis) {
  const pg::Vec3 axis = pg::Vec3(1, 2, -0.5).normalized();
  const pg::Quat expected(Eigen::AngleAxisd(0.7, axis));
  EXPECT_LT(pg::angle_between(pg::quat_from_rotation_vector(0.7 * axis), expected), 1e-12);
}

TEST(Quaternion, AngleBetweenIsSignInvariant) {
  const pg::Quat a(Eigen::AngleAxisd(0.4, pg::Vec3::UnitX()));
  const pg::Quat b(Eigen::AngleAxisd(0.1, pg::Vec3::UnitX()));
  const pg::Quat minus_b(-b.w(), -b.x(), -b.y(), -b.z());
  EXPECT_NEAR(pg::angle_between(a, b), 0.3, 1e-12);
  EXPECT_NEAR(pg::angle_between(a, minus_b), 0.3, 1e-12);
}

TEST(Quaternion, SameHemisphereFlipsOnlyWhenNeeded) {
  const pg::Quat ref = pg::Quat::Identity();
  const pg::Quat q(-0.9, 0.1, 0.0, 0.0);
  EXPECT_GT(pg::same_hemisphere(q, ref).w(), 0.0);
  EXPECT_EQ(pg::same_hemisphere(ref, ref).coeffs(), ref.coeffs());
}

TEST(Frames, EnuFromWorldMapsNorthWestUp) {
  // W's x is north (ENU y), W's y is west (ENU -x), z stays up.
  EXPECT_TRUE((pg::ENU_from_W() * pg::Vec3::UnitX()).isApprox(pg::Vec3::UnitY()));
  EXPECT_TRUE((pg::ENU_from_W() * pg::Vec3::UnitY()).isApprox(-pg::Vec3::UnitX()));
  EXPECT_TRUE((pg::ENU_from_W() * pg::Vec3::UnitZ()).isApprox(pg::Vec3::UnitZ()));
}
