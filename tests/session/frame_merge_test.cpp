// The frame merge's rule (session/frame_merge.hpp) on constructed conflicts, and FrameMerger's
// holding: a frame leaves once every contributing stage has passed it, once only.
#include "session/frame_merge.hpp"

#include <gtest/gtest.h>

namespace posefuse::session {
namespace {

using geometry::Quat;
using geometry::Vec3;

constexpr std::int64_t kT = 1'000'000;

FittedFrame fitted(std::int64_t t_us, bool lost, const Quat& fit_forearm_K_from_F) {
  FittedFrame f;
  f.lost = lost;
  f.estimate.t_us = t_us;
  f.estimate.fit_energy = lost ? 500.0 : 5.0;
  for (int j = 0; j < 24; ++j) f.estimate.smpl_joints.push_back({Vec3(0.01 * j, 0.0, 2.0), v1::FUSED, 1.0});
  for (int j = 0; j < 25; ++j) f.estimate.camera_joints.push_back({Vec3(0.0, 0.01 * j, 2.0), v1::FUSED, 0.5});
  f.estimate.forearms.push_back({v1::RIGHT, fit_forearm_K_from_F, 0.3, v1::FUSED, 1.0});
  return f;
}

FrameParts::Arm arm_estimate(std::int64_t t_us, forearm::PositionSource source, const Vec3& imu_K,
                             const Quat& K_from_F) {
  forearm::ArmFrameEstimate e{t_us, K_from_F, 0.1, imu_K, source};
  return {"arm_r", v1::RIGHT, e};
}

const Quat kImuForearm(Eigen::AngleAxisd(0.2, Vec3::UnitX()));
const Quat kFitForearm(Eigen::AngleAxisd(0.9, Vec3::UnitY()));

TEST(FrameMerge, TheForearmStagesOrientationAndStrapPositionBeatTheFitsCopy) {
  FrameParts parts;
  parts.t_us = kT;
  parts.fit = fitted(kT, false, kFitForearm);
  parts.arms.push_back(arm_estimate(kT, forearm::PositionSource::kVisual, Vec3(0.1, 0.2, 1.5), kImuForearm));
  const FrameEstimate merged = merge_frame(parts);
  ASSERT_EQ(merged.forearms.size(), 1u);  // one per arm, not one per stage
  EXPECT_TRUE(merged.forearms[0].K_from_F.isApprox(kImuForearm));
  EXPECT_DOUBLE_EQ(merged.forearms[0].pronation_rad, 0.1);
  ASSERT_EQ(merged.imu_positions.size(), 1u);
  EXPECT_EQ(merged.imu_positions[0].source, v1::VISUAL);
  EXPECT_TRUE(merged.imu_positions[0].p_K.isApprox(Vec3(0.1, 0.2, 1.5)));
  // The joints are the fit's, with its confidence.
  ASSERT_EQ(merged.smpl_joints.size(), 24u);
  EXPECT_DOUBLE_EQ(merged.smpl_joints[3].confidence, 1.0);
  EXPECT_DOUBLE_EQ(merged.fit_energy, 5.0);
}

TEST(FrameMerge, InsideAGapTheRecoveredTrajectoryBeatsTheLiveEstimate) {
  FrameParts parts;
  parts.t_us = kT;
  parts.arms.push_back(arm_estimate(kT, forearm::PositionSource::kPredicted, Vec3(0.5, 0.5, 1.0), kImuForearm));
  EXPECT_EQ(merge_frame(parts).imu_positions.at(0).source, v1::PREDICTED);
  parts.recovered.push_back({"arm_r", Vec3(0.1, 0.1, 1.1)});
  const FrameEstimate merged = merge_frame(parts);
  ASSERT_EQ(merged.imu_positions.size(), 1u);
  EXPECT_EQ(merged.imu_positions[0].source, v1::RECOVERED);
  EXPECT_TRUE(merged.imu_positions[0].p_K.isApprox(Vec3(0.1, 0.1, 1.1)));
  // Another arm's recovery is not this arm's.
  parts.recovered.front().device_id = "arm_l";
  EXPECT_EQ(merge_frame(parts).imu_positions.at(0).source, v1::PREDICTED);
}

TEST(FrameMerge, ALostFitKeepsItsJointsAtLowConfidence) {
  FrameParts parts;
  parts.t_us = kT;
  parts.fit = fitted(kT, true, kFitForearm);
  const FrameEstimate merged = merge_frame(parts);
  ASSERT_EQ(merged.smpl_joints.size(), 24u);
  ASSERT_EQ(merged.camera_joints.size(), 25u);
  for (const JointEstimate& j : merged.smpl_joints) EXPECT_LE(j.confidence, kLostFitConfidence);
  for (const JointEstimate& j : merged.camera_joints) EXPECT_LE(j.confidence, kLostFitConfidence);
  // No forearm stage result for the arm: the fit's forearm, at the lost fit's confidence.
  ASSERT_EQ(merged.forearms.size(), 1u);
  EXPECT_TRUE(merged.forearms[0].K_from_F.isApprox(kFitForearm));
  EXPECT_LE(merged.forearms[0].confidence, kLostFitConfidence);
}

TEST(FrameMerger, AFrameWaitsForEveryContributorThenLeavesOnce) {
  FrameMerger merger;
  merger.add(FramesDone{FrameSource::kForearm, kT - 1});
  merger.add(FramesDone{FrameSource::kBodyFit, kT - 1});
  ArmFrameEstimates arms{
      "arm_r",
      v1::RIGHT,
      {arm_estimate(kT, forearm::PositionSource::kPredicted, Vec3(0.5, 0.5, 1.0), kImuForearm).estimate}};
  merger.add(arms);
  merger.add(FramesDone{FrameSource::kForearm, kT});
  EXPECT_TRUE(merger.take_complete().empty());  // the fit has not passed kT
  EXPECT_EQ(merger.frames_held(), 1u);
  // A SMOOTHER segment over the frame arrives before the fit: the frame takes it.
  RecoveredSegment segment{"arm_r", v1::RIGHT, {forearm::RecoveryMethod::kSmoother, kT - 100'000, kT + 100'000, {}}};
  segment.segment.samples.push_back({kT - 100'000, Vec3(0.0, 0.0, 1.0), Vec3::Zero(), Vec3::Zero(), kImuForearm});
  segment.segment.samples.push_back({kT + 100'000, Vec3(0.2, 0.0, 1.0), Vec3::Zero(), Vec3::Zero(), kImuForearm});
  merger.add(segment);
  merger.add(fitted(kT, false, kFitForearm));
  merger.add(FramesDone{FrameSource::kBodyFit, kT});
  const std::vector<FrameEstimate> out = merger.take_complete();
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].t_us, kT);
  EXPECT_EQ(out[0].smpl_joints.size(), 24u);
  ASSERT_EQ(out[0].imu_positions.size(), 1u);
  EXPECT_EQ(out[0].imu_positions[0].source, v1::RECOVERED);
  EXPECT_TRUE(out[0].imu_positions[0].p_K.isApprox(Vec3(0.1, 0.0, 1.0)));  // halfway
  // A part for a frame already sent is counted, not a second result.
  merger.add(fitted(kT, false, kFitForearm));
  EXPECT_EQ(merger.late_parts(), 1u);
  EXPECT_TRUE(merger.finish().empty());
}

TEST(FrameMerger, AFrameLeavesIncompleteAfterTheLongestHold) {
  FrameMerger merger;
  merger.add(FramesDone{FrameSource::kForearm, INT64_MAX});
  merger.add(FramesDone{FrameSource::kBodyFit, 0});  // a fit that never says it passed
  merger.add(fitted(kT, false, kFitForearm));
  EXPECT_TRUE(merger.take_complete().empty());
  const auto later_us = kT + static_cast<std::int64_t>(kMaxHoldS * 1e6) + 1;
  merger.add(fitted(later_us, false, kFitForearm));
  const std::vector<FrameEstimate> out = merger.take_complete();
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].t_us, kT);
  EXPECT_EQ(merger.incomplete_frames(), 1u);
  EXPECT_EQ(merger.finish().size(), 1u);  // the end sends what is left
}

}  // namespace
}  // namespace posefuse::session
