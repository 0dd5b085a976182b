// forearm/visual_axis_correction.hpp: an IMU orientation with a constant tilt of K (the filter's
// inclination error, mapped through eq. 11) is turned onto the truth by the depth-measured forearm
// axes of a moving forearm; frames beyond the gate, bad segments and the unobservable roll about
// the forearm are left alone.
#include "forearm/visual_axis_correction.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "../imu/expect_error.hpp"
#include "synthetic_arm.hpp"

namespace posefuse::forearm {
namespace {

using testing::ArmMotion;

constexpr double kDeg = std::numbers::pi / 180.0;

Vec3 axis_of(const Quat& K_from_F) { return K_from_F * Vec3::UnitY(); }

double axis_angle_deg(const Quat& a, const Quat& b) {
  return std::acos(std::clamp(axis_of(a).dot(axis_of(b)), -1.0, 1.0)) / kDeg;
}

TEST(VisualAxisCorrection, ATiltOfKIsTakenOutByTheAxesOfAMovingForearm) {
  const ArmMotion motion;
  // The IMU's K_from_F is the truth turned by 6 deg about a fixed axis of K (not the forearm's).
  const Quat K_tilt(Eigen::AngleAxisd(6.0 * kDeg, Vec3(1.0, 0.2, 0.4).normalized()));
  VisualAxisCorrection correction;
  double first_error_deg = 0.0, last_error_deg = 0.0;
  for (int frame = 0; frame < 900; ++frame) {  // 30 s at 30 frames/s
    const double t = frame / 30.0;
    const Quat K_from_F_imu = K_tilt * motion.K_from_F(t);
    const double error_deg = geometry::angle_between(correction.apply(K_from_F_imu), motion.K_from_F(t)) / kDeg;
    if (frame == 0) first_error_deg = error_deg;
    last_error_deg = error_deg;
    EXPECT_TRUE(correction.observe(K_from_F_imu, motion.elbow(t), motion.wrist(t))) << "frame " << frame;
  }
  std::printf("K_from_F error: %.3f deg at the first frame, %.4f deg after 30 s\n", first_error_deg, last_error_deg);
  EXPECT_NEAR(first_error_deg, 6.0, 1e-9);
  // All three angles: the forearm's directions span enough of the sphere.
  EXPECT_LT(last_error_deg, 0.1);
  EXPECT_LT(geometry::angle_between(correction.K_correction(), K_tilt.conjugate()) / kDeg, 0.1);
  EXPECT_EQ(correction.frames_used(), 900u);
}

TEST(VisualAxisCorrection, EachFrameTakesGainTimesTheAxisAngle) {
  const Quat K_from_F = geometry::quat_from_rotation_vector(Vec3(0.3, -0.2, 0.5));
  const Vec3 elbow(0.1, 0.2, 1.9);
  // The depth axis 5 deg away from the IMU's, about an axis perpendicular to it.
  const Vec3 perpendicular = axis_of(K_from_F).cross(Vec3::UnitZ()).normalized();
  const Vec3 depth_axis = Eigen::AngleAxisd(5.0 * kDeg, perpendicular) * axis_of(K_from_F);
  VisualAxisCorrection correction(VisualAxisCorrectionOptions{.gain = 0.1});
  ASSERT_TRUE(correction.observe(K_from_F, elbow, elbow + 0.25 * depth_axis));
  EXPECT_NEAR(axis_angle_deg(correction.apply(K_from_F), K_from_F), 0.5, 1e-9);
  // The step turns the axis towards the depth axis, not away.
  EXPECT_NEAR(std::acos(axis_of(correction.apply(K_from_F)).dot(depth_axis)) / kDeg, 4.5, 1e-9);
}

TEST(VisualAxisCorrection, RollAboutTheForearmIsLeftAsItIs) {
  const Quat truth = geometry::quat_from_rotation_vector(Vec3(0.3, -0.2, 0.5));
  const Quat rolled = truth * Quat(Eigen::AngleAxisd(5.0 * kDeg, Vec3::UnitY()));  // about y_F
  const Vec3 elbow(0.1, 0.2, 1.9);
  VisualAxisCorrection correction;
  for (int i = 0; i < 100; ++i) ASSERT_TRUE(correction.observe(rolled, elbow, elbow + 0.25 * axis_of(truth)));
  EXPECT_LT(geometry::angle_between(correction.K_correction(), Quat::Identity()), 1e-9);
  EXPECT_NEAR(geometry::angle_between(correction.apply(rolled), truth) / kDeg, 5.0, 1e-9);
}

TEST(VisualAxisCorrection, FramesBeyondTheGateAndBadSegmentsAreNotUsed) {
  const Quat K_from_F = Quat::Identity();
  const Vec3 elbow(0.0, 0.0, 2.0);
  VisualAxisCorrection correction;  // gate 8 deg
  const Vec3 nine_deg = Eigen::AngleAxisd(9.0 * kDeg, Vec3::UnitX()) * Vec3::UnitY();
  EXPECT_FALSE(correction.observe(K_from_F, elbow, elbow + 0.25 * nine_deg));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(correction.observe(K_from_F, Vec3(nan, 0.0, 2.0), elbow + Vec3(0.0, 0.25, 0.0)));
  EXPECT_FALSE(correction.observe(K_from_F, elbow, Vec3(0.0, nan, 2.0)));
  EXPECT_FALSE(correction.observe(Quat(nan, 0.0, 0.0, 0.0), elbow, elbow + Vec3(0.0, 0.25, 0.0)));
  EXPECT_FALSE(correction.observe(K_from_F, elbow, elbow + Vec3(0.0, 0.04, 0.0)));  // 4 cm: too short
  EXPECT_EQ(correction.frames_used(), 0u);
  EXPECT_EQ(correction.K_correction().coeffs(), Quat::Identity().coeffs());
  // Within the gate: used.
  const Vec3 seven_deg = Eigen::AngleAxisd(7.0 * kDeg, Vec3::UnitX()) * Vec3::UnitY();
  EXPECT_TRUE(correction.observe(K_from_F, elbow, elbow + 0.25 * seven_deg));
  EXPECT_EQ(correction.frames_used(), 1u);
}

TEST(VisualAxisCorrection, BadOptionsAreRefused) {
  using posefuse::testing::expect_error;
  for (const double gain : {0.0, -0.1, 1.5, std::numeric_limits<double>::quiet_NaN()}) {
    expect_error([&] { VisualAxisCorrection c(VisualAxisCorrectionOptions{.gain = gain}); },
                 ErrorCode::kInvalidArgument, "VisualAxisCorrectionOptions.gain");
  }
  for (const double max_angle : {0.0, 2.0, std::numeric_limits<double>::infinity()}) {
    expect_error([&] { VisualAxisCorrection c(VisualAxisCorrectionOptions{.max_angle_rad = max_angle}); },
                 ErrorCode::kInvalidArgument, "VisualAxisCorrectionOptions.max_angle_rad");
  }
}

}  // namespace
}  // namespace posefuse::forearm
