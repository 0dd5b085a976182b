// One arm's calibration (forearm/arm_calibration.hpp, forearm_model.hpp calibrate_forearm): the
// strap frames' full model or eq. 9 alone, and the holds no human arm in the pose can give,
// refused by name.
#include <gtest/gtest.h>

#include <numbers>

#include "../imu/expect_error.hpp"
#include "forearm/arm_calibration.hpp"
#include "synthetic_arm.hpp"

namespace posefuse::forearm {
namespace {

using namespace posefuse::forearm::testing;
using posefuse::testing::expect_error;
constexpr double kDeg = std::numbers::pi / 180.0;

// The shoulder-elbow distance of the hold is d_ul: 7 cm (the shoulder taken at the elbow, as
// a garbled skeleton gives) and 60 cm are no arm; the bounds themselves are arms.
TEST(ArmCalibration, AnUpperArmNoHumanHasIsRefusedByItsLength) {
  const ArmMotion motion;
  const auto with_upper_arm = [&](double length_m) {
    std::vector<CalibrationFrame> frames = held_pose_frames(motion);
    for (CalibrationFrame& f : frames) {
      f.shoulder_K = f.elbow_K + length_m * (motion.shoulder(0.3) - motion.elbow(0.3)).normalized();
    }
    return frames;
  };
  expect_error([&] { calibrate_forearm(with_upper_arm(0.07), motion.K_from_W); }, ErrorCode::kFailedPrecondition,
               "frames", "upper arm (shoulder to elbow) of 7.0 cm, outside 15-50 cm");
  expect_error([&] { calibrate_forearm(with_upper_arm(0.60), motion.K_from_W); }, ErrorCode::kFailedPrecondition,
               "frames", "of 60.0 cm");
  EXPECT_NEAR(calibrate_forearm(with_upper_arm(0.151), motion.K_from_W).model.d_ul_m, 0.151, 1e-9);
  EXPECT_NEAR(calibrate_forearm(with_upper_arm(0.499), motion.K_from_W).model.d_ul_m, 0.499, 1e-9);
}

// The IMU still while the skeleton's forearm turns +-a about its axis from frame to frame: the
// per-frame mountings spread a (RMS). 10 degrees is a noisy hold and calibrates; 25 degrees is
// not one pose and is refused, naming the spread.
TEST(ArmCalibration, AHoldWhoseMountingsSpreadIsRefusedBySpread) {
  const ArmMotion motion;
  const auto with_spread = [&](double angle_rad) {
    std::vector<CalibrationFrame> frames = held_pose_frames(motion);
    for (std::size_t k = 0; k < frames.size(); ++k) {
      const double sign = k % 2 == 0 ? 1.0 : -1.0;
      frames[k].K_from_F_sdk =
          frames[k].K_from_F_sdk * geometry::quat_from_rotation_vector(sign * angle_rad * Vec3::UnitY());
    }
    return frames;
  };
  const ForearmCalibration noisy = calibrate_forearm(with_spread(10.0 * kDeg), motion.K_from_W);
  EXPECT_NEAR(noisy.F_from_A_spread_rad, 10.0 * kDeg, 1e-6);
  EXPECT_LT(geometry::angle_between(noisy.model.F_from_A, motion.model.F_from_A), 1e-6);
  expect_error([&] { calibrate_forearm(with_spread(25.0 * kDeg), motion.K_from_W); }, ErrorCode::kFailedPrecondition,
               "frames", "mountings (eq. 9) spread 25.0 deg RMS, above 15");
}

// The strap seen at 5 of 40 frames: eq. 9 from every frame in the pose, no model, and why;
// seen at every frame: the full model. The held orientation is the pose's.
TEST(ArmCalibration, TooFewStrapFramesGiveOrientationOnly) {
  const ArmMotion motion;
  CalibrationFrames frames;
  frames.without_strap = held_pose_frames(motion);
  frames.with_strap.assign(frames.without_strap.begin(), frames.without_strap.begin() + 5);
  const ArmCalibration orientation_only = calibrate_arm(frames, motion.K_from_W, {});
  EXPECT_FALSE(orientation_only.has_model);
  EXPECT_NE(orientation_only.strap_not_seen.find("seen in 5 of 40 calibration frames"), std::string::npos)
      << orientation_only.strap_not_seen;
  EXPECT_EQ(orientation_only.calibration.frame_count, 40u);
  EXPECT_LT(geometry::angle_between(orientation_only.K_from_F_held, motion.K_from_F(0.3)), 1e-9);

  frames.with_strap = frames.without_strap;
  const ArmCalibration full = calibrate_arm(frames, motion.K_from_W, {});
  EXPECT_TRUE(full.has_model);
  EXPECT_TRUE(full.strap_not_seen.empty());
  EXPECT_NEAR(full.calibration.model.r_m, motion.model.r_m, 1e-9);
}

// Neither set holds still long enough: refused with the reason of the frames in the pose.
TEST(ArmCalibration, NoHoldIsRefusedWithTheReason) {
  const ArmMotion motion;
  CalibrationFrames frames;
  const std::vector<CalibrationFrame> held = held_pose_frames(motion);
  frames.without_strap.assign(held.begin(), held.begin() + 10);
  expect_error([&] { calibrate_arm(frames, motion.K_from_W, {}); }, ErrorCode::kFailedPrecondition, "frames",
               "held still for 10 frames; need 15");
}

}  // namespace
}  // namespace posefuse::forearm
