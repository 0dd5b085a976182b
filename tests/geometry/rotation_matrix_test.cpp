#include "geometry/rotation_matrix.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "common/error.hpp"

namespace pg = posefuse::geometry;

namespace {
void expect_same_rotation(const pg::Quat& a, const pg::Quat& b) {
  EXPECT_NEAR(std::abs(a.dot(b)), 1.0, 1e-12) << a.coeffs().transpose() << " vs " << b.coeffs().transpose();
  EXPECT_NEAR(a.norm(), 1.0, 1e-14);
}
}  // namespace

TEST(QuatFromRotationMatrix, AgreesWithEigenForRandomRotations) {
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < 2000; ++i) {
    const pg::Quat truth = pg::Quat(n(rng), n(rng), n(rng), n(rng)).normalized();
    const pg::Mat3 R = truth.toRotationMatrix();
    expect_same_rotation(pg::quat_from_rotation_matrix(R), pg::Quat(R));
    expect_same_rotation(pg::quat_from_rotation_matrix(R), truth);
  }
}

// Each of van Waveren's four branches: trace > 0, and 180 degree turns where x, y or z is the
// largest component (trace = -1).
TEST(QuatFromRotationMatrix, CoversEveryPivotBranch) {
  const pg::Vec3 axes[] = {pg::Vec3(1, 0.2, -0.1).normalized(), pg::Vec3(0.1, 1, 0.3).normalized(),
                           pg::Vec3(-0.2, 0.1, 1).normalized()};
  for (const pg::Vec3& axis : axes) {
    for (double angle : {0.3, 3.0, double(EIGEN_PI)}) {
      const pg::Quat truth(Eigen::AngleAxisd(angle, axis));
      expect_same_rotation(pg::quat_from_rotation_matrix(truth.toRotationMatrix()), truth);
    }
  }
  expect_same_rotation(pg::quat_from_rotation_matrix(pg::Mat3::Identity()), pg::Quat::Identity());
}

TEST(QuatFromRotationMatrix, RejectsNonFinite) {
  pg::Mat3 R = pg::Mat3::Identity();
  R(1, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(pg::quat_from_rotation_matrix(R), posefuse::Error);
}
