// Forearm orientation per IMU sample (eq. 11) and the pronation angle.
#include <gtest/gtest.h>

#include <numbers>

#include "../imu/expect_error.hpp"
#include "forearm/forearm_model.hpp"
#include "forearm/forearm_orientation.hpp"
#include "geometry/rotation_matrix.hpp"

namespace posefuse::forearm {
namespace {

using posefuse::testing::expect_error;
constexpr double kDeg = std::numbers::pi / 180.0;

Quat rot(double angle, const Vec3& axis) { return Quat(Eigen::AngleAxisd(angle, axis.normalized())); }

TEST(ForearmOrientation, TwistIgnoresSwing) {
  for (double twist : {-170.0, -60.0, 0.0, 35.0, 120.0, 179.0}) {
    for (const Vec3& swing_axis : {Vec3(1, 0, 0), Vec3(0.6, 0, -0.8), Vec3(0, 0, 1)}) {
      const Quat q = rot(50 * kDeg, swing_axis) * rot(twist * kDeg, Vec3::UnitY());
      EXPECT_NEAR(twist_about_y(q) / kDeg, twist, 1e-9);
      EXPECT_NEAR(twist_about_y(Quat(-q.coeffs())) / kDeg, twist, 1e-9);  // sign-invariant
    }
  }
}

TEST(ForearmOrientation, PronationSignPerArm) {
  const Quat reference = rot(0.7, Vec3(1, 2, 3));
  // Right arm: supination is a positive turn about +y_F (thumb outwards), so pronation < 0 there.
  const Quat supinated = reference * rot(30 * kDeg, Vec3::UnitY());
  EXPECT_NEAR(pronation_angle(reference, supinated, Side::kRight) / kDeg, -30.0, 1e-9);
  EXPECT_NEAR(pronation_angle(reference, supinated, Side::kLeft) / kDeg, 30.0, 1e-9);
  // A pure swing (elbow flexion) leaves the pronation angle at zero.
  EXPECT_NEAR(pronation_angle(reference, reference * rot(80 * kDeg, Vec3::UnitX()), Side::kRight), 0.0, 1e-12);
}

TEST(ForearmOrientation, CalibrationPoseFrame) {
  // Paper 1 Fig. 3b seen from the camera: upper arm sideways (to the camera's left, +x_K),
  // forearm straight up, 2 m away. The arm's plane is z_K = 2; the back of the hand faces away
  // from the camera: x_F = +z_K, y_F = +y_K, z_F = x x y = -x_K (the thumb towards the head).
  const Vec3 shoulder(0.0, 0.2, 2.0), elbow(0.3, 0.2, 2.0), wrist(0.3, 0.45, 2.0);
  const Quat K_from_F = K_from_F_calibration_pose(shoulder, elbow, wrist);
  EXPECT_LT((K_from_F * Vec3::UnitX() - Vec3::UnitZ()).norm(), 1e-12);
  EXPECT_LT((K_from_F * Vec3::UnitY() - Vec3::UnitY()).norm(), 1e-12);
  EXPECT_LT((K_from_F * Vec3::UnitZ() + Vec3::UnitX()).norm(), 1e-12);
  // The same with the shoulder on the other side (a left arm): x_F still points away.
  const Quat left = K_from_F_calibration_pose(Vec3(0.6, 0.2, 2.0), elbow, wrist);
  EXPECT_LT((left * Vec3::UnitX() - Vec3::UnitZ()).norm(), 1e-12);
  expect_error([&] { K_from_F_calibration_pose(shoulder, elbow, Vec3(0.6, 0.2, 2.0)); }, ErrorCode::kInvalidArgument,
               "shoulder_K/elbow_K/wrist_K", "straighter");
  // An arm plane that contains the camera ray (the arm points at the camera in a vertical plane).
  expect_error([&] { K_from_F_calibration_pose(Vec3(0, 0.2, 2.3), Vec3(0, 0.2, 2.0), Vec3(0, 0.45, 2.0)); },
               ErrorCode::kInvalidArgument, "shoulder_K/elbow_K/wrist_K", "camera ray");
  expect_error([&] { K_from_F_calibration_pose(Vec3(NAN, 0, 1), elbow, wrist); }, ErrorCode::kInvalidArgument,
               "shoulder_K");
}

TEST(ForearmOrientation, SampleFollowsEq11) {
  const Quat K_from_W = rot(-std::numbers::pi / 2, Vec3::UnitX()) * rot(0.4, Vec3::UnitZ());
  const Quat F_from_A = rot(0.3, Vec3(1, -1, 2));
  const Quat K_from_F_ref = rot(0.2, Vec3(0, 1, 1));
  // The forearm rolls by -40 degrees (pronation for a right arm) from the reference.
  const Quat K_from_F = K_from_F_ref * rot(-40 * kDeg, Vec3::UnitY());
  const Quat W_from_A = K_from_W.conjugate() * K_from_F * F_from_A;
  const ForearmSample s = forearm_sample(K_from_W, W_from_A, F_from_A, K_from_F_ref, Side::kRight);
  // angle_between resolves about 3e-8 rad (acos near 1).
  EXPECT_LT(geometry::angle_between(s.K_from_F, K_from_F), 1e-7);
  EXPECT_LT(geometry::angle_between(s.K_from_A, K_from_F * F_from_A), 1e-7);
  EXPECT_NEAR(s.pronation_rad / kDeg, 40.0, 1e-7);
}

}  // namespace
}  // namespace posefuse::forearm
