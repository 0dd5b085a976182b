// select_calibration_frames (forearm/calibration_frames.hpp) on constructed frames: which frames
// make the calibration, and why the others do not.
#include "forearm/calibration_frames.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace posefuse::forearm {
namespace {

// An arm in the calibration pose (paper 1 Fig. 3b), up = +y: the upper arm down from the
// shoulder, the forearm raised from the elbow.
ArmFrame pose_frame(std::int64_t t_us, bool strap) {
  ArmFrame f;
  f.t_us = t_us;
  f.shoulder_K = Vec3(0.2, 0.3, 2.0);
  f.elbow_K = Vec3(0.2, 0.0, 1.9);
  f.wrist_K = Vec3(0.2, 0.25, 1.75);
  f.shoulder_tracked = f.forearm_tracked = true;
  if (strap) f.strap_K = f.elbow_K + 0.6 * (f.wrist_K - f.elbow_K);
  return f;
}

TEST(CalibrationFrames, FramesInThePoseWithTheImuAreKeptTheOthersCounted) {
  const Vec3 up_K = Vec3::UnitY();
  std::vector<ArmFrame> frames;
  for (int k = 0; k < 6; ++k) frames.push_back(pose_frame(k * 33'333, k % 2 == 0));
  ArmFrame resting = pose_frame(6 * 33'333, true);
  resting.wrist_K = resting.elbow_K + Vec3(0.0, -0.25, 0.0);  // hanging at the side
  frames.push_back(resting);
  ArmFrame overhead = pose_frame(6 * 33'333 + 10'000, true);
  overhead.elbow_K = overhead.shoulder_K + Vec3(0.05, 0.28, 0.0);  // raised straight up, the SDK's bend
  overhead.wrist_K = overhead.elbow_K + Vec3(0.1, 0.23, 0.0);
  frames.push_back(overhead);
  ArmFrame straight = pose_frame(6 * 33'333 + 20'000, true);
  straight.elbow_K = straight.shoulder_K + 0.28 * Vec3(std::cos(0.7), std::sin(0.7), 0.0);  // raised 40 degrees
  straight.wrist_K = straight.elbow_K + 0.25 * Vec3(std::cos(0.87), std::sin(0.87), 0.0);   // 10 degrees more
  frames.push_back(straight);
  ArmFrame untracked = pose_frame(7 * 33'333, true);
  untracked.forearm_tracked = false;
  frames.push_back(untracked);
  frames.push_back(pose_frame(8 * 33'333, true));   // no IMU sample there
  frames.push_back(pose_frame(20 * 33'333, true));  // after the window
  const auto W_from_A_at = [](std::int64_t t_us) -> std::optional<Quat> {
    if (t_us > 7 * 33'333) return std::nullopt;
    return Quat::Identity();
  };
  CalibrationFrameOptions options;
  options.upper_arm_from_depth = false;
  const CalibrationFrames c = select_calibration_frames(frames, 10 * 33'333, up_K, W_from_A_at, options);
  EXPECT_EQ(c.without_strap.size(), 6u);
  EXPECT_EQ(c.with_strap.size(), 3u);
  EXPECT_EQ(c.not_raised, 1u);
  EXPECT_EQ(c.overhead, 1u);
  EXPECT_EQ(c.straight, 1u);
  EXPECT_FALSE(c.depth_upper_arm);
  // Without a strap the strap point is a placeholder on the forearm.
  EXPECT_TRUE(c.without_strap[1].strap_K.isApprox(frames[1].elbow_K + 0.8 * (frames[1].wrist_K - frames[1].elbow_K)));
}

TEST(CalibrationFrames, TheUpperArmFromDepthIsUsedOnlyWithEnoughFrames) {
  std::vector<ArmFrame> frames;
  for (int k = 0; k < 4; ++k) {
    frames.push_back(pose_frame(k * 33'333, true));
    frames.back().upper_arm_direction_K = Vec3(0.0, -1.0, 0.0);
  }
  frames.push_back(pose_frame(4 * 33'333, true));  // no depth upper arm
  const auto W_from_A_at = [](std::int64_t) -> std::optional<Quat> { return Quat::Identity(); };
  CalibrationFrameOptions options;
  options.min_upper_arm_frames = 4;
  const CalibrationFrames with_depth =
      select_calibration_frames(frames, 1'000'000, Vec3::UnitY(), W_from_A_at, options);
  EXPECT_TRUE(with_depth.depth_upper_arm);
  EXPECT_EQ(with_depth.upper_arm_frames, 4u);
  EXPECT_EQ(with_depth.without_strap.size(), 4u);  // the frame without it is left out
  options.min_upper_arm_frames = 5;
  const CalibrationFrames without = select_calibration_frames(frames, 1'000'000, Vec3::UnitY(), W_from_A_at, options);
  EXPECT_FALSE(without.depth_upper_arm);
  EXPECT_EQ(without.without_strap.size(), 5u);  // the SDK shoulder for all
}

}  // namespace
}  // namespace posefuse::forearm
