// Chordal mean and RMS angle of a set of rotations (geometry/rotation_mean.hpp).
#include <gtest/gtest.h>

#include <vector>

#include "geometry/rotation_mean.hpp"

namespace posefuse::geometry {
namespace {

// Rotations symmetric about a centre average to the centre whatever sign each quaternion has,
// and their spread is their common angle from it.
TEST(RotationMean, SymmetricRotationsAverageToTheirCentre) {
  const Quat centre = quat_from_rotation_vector(Vec3(0.4, -1.1, 0.7));
  const double angle = 0.2;
  std::vector<Quat> rotations;
  for (int k = 0; k < 3; ++k) {
    const Vec3 axis = Vec3::Unit(k);
    rotations.push_back(centre * quat_from_rotation_vector(angle * axis));
    const Quat opposite = centre * quat_from_rotation_vector(-angle * axis);
    rotations.push_back(Quat(-opposite.coeffs()));  // the same rotation, the other hemisphere
  }
  const Quat mean = chordal_mean(rotations);
  EXPECT_LT(angle_between(mean, centre), 1e-12);
  EXPECT_NEAR(rms_angle_rad(rotations, mean), angle, 1e-12);
  EXPECT_EQ(rms_angle_rad({centre}, centre), 0.0);
}

}  // namespace
}  // namespace posefuse::geometry
