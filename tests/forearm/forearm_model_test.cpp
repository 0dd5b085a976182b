// Rigid forearm model (II-H, eqs. 9-11) and the occlusion tests (II-J) on exact geometry.
#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "../imu/expect_error.hpp"
#include "forearm/forearm_model.hpp"
#include "forearm/occlusion_tests.hpp"
#include "synthetic_arm.hpp"

namespace posefuse::forearm {
namespace {

using namespace posefuse::forearm::testing;
using posefuse::testing::expect_error;
constexpr double kDeg = std::numbers::pi / 180.0;

TEST(ForearmModel, Eq9And11RoundTrip) {
  const ArmMotion motion;
  const Quat K_from_F = motion.K_from_F(0.7);
  const Quat W_from_A = motion.K_from_W.conjugate() * K_from_F * motion.model.F_from_A;
  const Quat F_from_A = F_from_A_calibration(K_from_F, motion.K_from_W, W_from_A);
  EXPECT_LT(geometry::angle_between(F_from_A, motion.model.F_from_A), 1e-9);
  EXPECT_LT(geometry::angle_between(K_from_F_from_imu(motion.K_from_W, W_from_A, F_from_A), K_from_F), 1e-9);
}

TEST(ForearmModel, Eq10FromAnyStrapPoint) {
  const ArmMotion motion;
  for (double t : {0.3, 1.1, 2.4}) {
    const Quat K_from_F = motion.K_from_F(t);
    const Vec3 elbow = motion.elbow(t), wrist = motion.wrist(t);
    // A point on the strap surface at another angle around the core still projects to F_o.
    const Vec3 strap = elbow + K_from_F * Vec3(0.02, motion.model.d_se_m, 0.02);
    const Vec3 imu = imu_position_from_strap(strap, elbow, wrist, K_from_F, motion.model.r_m);
    EXPECT_LT((imu - motion.imu_position(t)).norm(), 1e-12);
  }
  expect_error([] { imu_position_from_strap(Vec3::Zero(), Vec3::Ones(), Vec3::Ones(), Quat::Identity(), 0.03); },
               ErrorCode::kInvalidArgument, "elbow_K/wrist_K");
  expect_error([] { imu_position_from_strap(Vec3::Constant(NAN), Vec3::Zero(), Vec3::Ones(), Quat::Identity(), 0.03); },
               ErrorCode::kInvalidArgument, "strap_K");
}

// Calibration pose: the arm moves, holds still for 1 s (30 frames), moves again. Joints and
// strap carry 3 mm noise, the SDK orientation 3 degrees: averaged over 30 frames that is
// ~0.6 mm and ~0.6 degrees (per axis ~0.3); bounds 3 mm and 1.5 degrees.
TEST(ForearmModel, CalibrationAveragesTheStillFrames) {
  const ArmMotion motion;
  std::mt19937 rng(5);
  std::normal_distribution<double> n01(0.0, 1.0);
  auto noise = [&](double sigma) -> Vec3 {
    const double x = n01(rng), y = n01(rng), z = n01(rng);
    return Vec3(x, y, z) * sigma;
  };
  std::vector<CalibrationFrame> frames;
  for (int k = 0; k < 60; ++k) {
    // Moving before frame 15 and after frame 44, the pose of t = 0.3 s held in between.
    const double tt = k < 15 ? 0.06 * k - 0.6 : k < 45 ? 0.3 : 0.3 + 0.06 * (k - 44);
    CalibrationFrame f;
    f.t_us = k * 33'333;
    const Quat K_from_F = motion.K_from_F(tt);
    f.shoulder_K = motion.shoulder(tt) + noise(0.003);
    f.elbow_K = motion.elbow(tt) + noise(0.003);
    f.wrist_K = motion.wrist(tt) + noise(0.003);
    f.strap_K = motion.imu_position(tt) + noise(0.003);
    f.K_from_F_sdk = geometry::quat_from_rotation_vector(noise(3.0 * kDeg / std::sqrt(3.0))) * K_from_F;
    f.W_from_A = motion.K_from_W.conjugate() * K_from_F * motion.model.F_from_A;
    frames.push_back(f);
  }
  const ForearmCalibration c = calibrate_forearm(frames, motion.K_from_W);
  EXPECT_GE(c.frame_count, 28u);
  EXPECT_LE(c.frame_count, 31u);
  EXPECT_NEAR(c.model.r_m, motion.model.r_m, 0.003);
  EXPECT_NEAR(c.model.d_se_m, motion.model.d_se_m, 0.003);
  EXPECT_NEAR(c.model.d_sw_m, motion.model.d_sw_m, 0.003);
  EXPECT_NEAR(c.model.d_ul_m, motion.model.d_ul_m, 0.003);
  EXPECT_LT(geometry::angle_between(c.model.F_from_A, motion.model.F_from_A), 1.5 * kDeg);
  EXPECT_GT(c.F_from_A_spread_rad, 1.0 * kDeg);  // the SDK noise is visible in the spread

  // Too short a hold is refused.
  std::vector<CalibrationFrame> short_hold(frames.begin() + 10, frames.begin() + 22);
  expect_error([&] { calibrate_forearm(short_hold, motion.K_from_W); }, ErrorCode::kFailedPrecondition, "frames");
  frames[20].strap_K.x() = NAN;
  expect_error([&] { calibrate_forearm(frames, motion.K_from_W); }, ErrorCode::kInvalidArgument, "frames[20].strap_K");
}

// d_ul comes from the SDK's shoulder and elbow, whose per-session biases the hold's average keeps.
// Over 400 simulated holds whose two joints carry isotropic biases of 3D RMS camera_joint_error_m,
// the RMS error of d_ul matches the claimed uncertainty (sampling error of an RMS over 400
// draws: ~3.5 %; bound 10 %).
TEST(ForearmModel, UpperArmUncertaintyMatchesTheCameraJointsBias) {
  const ArmMotion motion;
  CalibrationOptions options;
  options.min_upper_arm_m = 0.0;  // the tails of the draws stay in (refusals have their own test)
  options.max_upper_arm_m = 1.0;
  std::mt19937 rng(11);
  std::normal_distribution<double> per_axis(0.0, options.camera_joint_error_m / std::sqrt(3.0));
  const auto bias = [&] { return Vec3(per_axis(rng), per_axis(rng), per_axis(rng)); };
  double sum_squared_error = 0.0, claimed = 0.0;
  constexpr int kHolds = 400;
  for (int hold = 0; hold < kHolds; ++hold) {
    const Vec3 shoulder_bias = bias(), elbow_bias = bias();
    std::vector<CalibrationFrame> frames;
    for (int k = 0; k < 20; ++k) {
      CalibrationFrame f;
      f.t_us = k * 33'333;
      f.shoulder_K = motion.shoulder(0.3) + shoulder_bias;
      f.elbow_K = motion.elbow(0.3) + elbow_bias;
      f.wrist_K = motion.wrist(0.3);
      f.strap_K = motion.imu_position(0.3);
      f.K_from_F_sdk = motion.K_from_F(0.3);
      f.W_from_A = motion.K_from_W.conjugate() * f.K_from_F_sdk * motion.model.F_from_A;
      frames.push_back(f);
    }
    const ForearmCalibration c = calibrate_forearm(frames, motion.K_from_W, options);
    sum_squared_error += std::pow(c.model.d_ul_m - motion.model.d_ul_m, 2);
    claimed = c.d_ul_uncertainty_m;
  }
  const double rms = std::sqrt(sum_squared_error / kHolds);
  EXPECT_NEAR(claimed, std::sqrt(2.0 / 3.0) * options.camera_joint_error_m, 1e-12);
  EXPECT_NEAR(rms / claimed, 1.0, 0.10) << "RMS " << rms << " m, claimed " << claimed << " m";
}

// The SDK's joints wander while the arm is still (a bias turning at ~3 cm/s, up to 4 cm from the
// first frame, beyond the old 2 cm radius): the arm IMU keeps
// the whole 2 s hold (60 frames) one still run; an IMU that turns 5 degrees halfway splits it.
TEST(ForearmModel, StillHoldFollowsTheImuWhileSdkJointsWander) {
  const ArmMotion motion;
  std::vector<CalibrationFrame> frames;
  for (int k = 0; k < 60; ++k) {
    const double t = k / 30.0;
    const Vec3 wander = 0.02 * Vec3(std::cos(1.6 * t) - 1.0, std::sin(1.6 * t), 0.0);  // 3.2 cm/s, up to 4 cm
    const Quat K_from_F = motion.K_from_F(0.3);
    CalibrationFrame f;
    f.t_us = k * 33'333;
    f.shoulder_K = motion.shoulder(0.3) + wander;
    f.elbow_K = motion.elbow(0.3) + wander;
    f.wrist_K = motion.wrist(0.3) - wander;
    f.strap_K = motion.imu_position(0.3);
    f.K_from_F_sdk = K_from_F;
    f.W_from_A = motion.K_from_W.conjugate() * K_from_F * motion.model.F_from_A;
    frames.push_back(f);
  }
  EXPECT_EQ(calibrate_forearm(frames, motion.K_from_W).frame_count, 60u);
  for (std::size_t k = 30; k < frames.size(); ++k) {
    frames[k].W_from_A = frames[k].W_from_A * geometry::quat_from_rotation_vector(Vec3(0.0, 5.0 * kDeg, 0.0));
  }
  EXPECT_EQ(calibrate_forearm(frames, motion.K_from_W).frame_count, 30u);
}

// A wrist measured in depth jumps along the forearm (~11 cm: the hand's widening seen in some
// frames, the fingertips taken in others): the hold stays one run. A wrist 6 cm off the line
// sideways still ends it.
TEST(ForearmModel, StillHoldKeepsTheRunWhenTheWristMovesAlongTheForearm) {
  const ArmMotion motion;
  std::vector<CalibrationFrame> frames = held_pose_frames(motion);
  const Vec3 along = (motion.wrist(0.3) - motion.elbow(0.3)).normalized();
  for (std::size_t k = 0; k < frames.size(); ++k) frames[k].wrist_K += ((k % 3 == 1) ? 0.11 : 0.0) * along;
  const ForearmCalibration c = calibrate_forearm(frames, motion.K_from_W);
  EXPECT_EQ(c.frame_count, 40u);
  // d_sw from the nearer group (the hand's widening), not the mean (3.7 cm long here).
  EXPECT_NEAR(c.model.d_sw_m, motion.model.d_sw_m, 0.002);
  const Vec3 sideways = (motion.wrist(0.3) - motion.elbow(0.3)).unitOrthogonal();
  frames[20].wrist_K += 0.06 * sideways;
  EXPECT_EQ(calibrate_forearm(frames, motion.K_from_W).frame_count, 20u);
}

// d_sw of a hold: one frame with the fingertips 8 cm beyond the wrist is left out, two frames
// nearer than the rest are too few to be the wrist (the farther group is used), and one group with
// 1.5 cm of noise is averaged.
TEST(ForearmModel, WristDistanceOfAHoldUsesTheNearerGroup) {
  const ArmMotion motion;
  const Vec3 along = (motion.wrist(0.3) - motion.elbow(0.3)).normalized();
  const auto frames_with = [&](auto wrist_offset_m) {
    std::vector<CalibrationFrame> frames = held_pose_frames(motion);
    for (std::size_t k = 0; k < frames.size(); ++k) frames[k].wrist_K += wrist_offset_m(static_cast<int>(k)) * along;
    return frames;
  };
  const auto one_far = frames_with([](int k) { return k == 17 ? 0.08 : 0.0; });
  EXPECT_NEAR(calibrate_forearm(one_far, motion.K_from_W).model.d_sw_m, motion.model.d_sw_m, 1e-9);
  const auto two_near = frames_with([](int k) { return k == 5 || k == 6 ? 0.0 : 0.09; });
  EXPECT_NEAR(calibrate_forearm(two_near, motion.K_from_W).model.d_sw_m, motion.model.d_sw_m + 0.09, 1e-9);
  const auto noisy = frames_with([](int k) { return 0.015 * std::sin(1.7 * k); });
  double mean_offset = 0.0;
  for (int k = 0; k < 40; ++k) mean_offset += 0.015 * std::sin(1.7 * k) / 40.0;
  EXPECT_NEAR(calibrate_forearm(noisy, motion.K_from_W).model.d_sw_m, motion.model.d_sw_m + mean_offset, 1e-9);
}

TEST(OcclusionTests, ForearmDirectionWithin30Degrees) {
  const Quat K_from_F = Quat::Identity();  // IMU forearm axis = K's y
  const Vec3 elbow(0.0, 0.0, 2.0);
  for (double deg : {0.0, 20.0, 29.0, 31.0, 60.0}) {
    const Vec3 wrist = elbow + 0.26 * Vec3(std::sin(deg * kDeg), std::cos(deg * kDeg), 0.0);
    const Vec3 strap = elbow + 0.85 * (wrist - elbow);
    const VisualCheck c = check_visual_forearm(elbow, wrist, strap, K_from_F);
    EXPECT_NEAR(c.direction_angle_rad, deg * kDeg, 1e-9);
    EXPECT_EQ(c.accepted(), deg < 30.0) << deg;
    if (deg > 30.0) {
      EXPECT_EQ(c.rejection, VisualRejection::kDirectionDisagrees);
    }
  }
}

TEST(OcclusionTests, GrazingViewIsRejected) {
  // Forearm pointing at the camera: along the ray to its midpoint.
  const Vec3 elbow(0.0, 0.0, 2.0), wrist(0.0, 0.0, 1.74);
  const Quat K_from_F = Quat::FromTwoVectors(Vec3::UnitY(), wrist - elbow);
  const VisualCheck along = check_visual_forearm(elbow, wrist, elbow + 0.85 * (wrist - elbow), K_from_F);
  EXPECT_NEAR(along.ray_angle_rad, 0.0, 1e-9);
  EXPECT_EQ(along.rejection, VisualRejection::kGrazingView);
  // 25 degrees off the ray passes, 15 degrees does not.
  for (double deg : {15.0, 25.0}) {
    const Vec3 dir(std::sin(deg * kDeg), 0.0, -std::cos(deg * kDeg));
    const Vec3 w = elbow + 0.26 * dir;
    const Quat q = Quat::FromTwoVectors(Vec3::UnitY(), dir);
    const VisualCheck c = check_visual_forearm(elbow, w, elbow + 0.85 * (w - elbow), q);
    EXPECT_EQ(c.accepted(), deg > 20.0) << deg << " ray angle " << c.ray_angle_rad / kDeg;
  }
}

// Beyond the paper: eq. 10 from the strap against eq. 10 from the SDK elbow (13 cm).
TEST(OcclusionTests, StrapAgainstTheSdkElbowsEstimate) {
  const Vec3 imu(0.1, 0.2, 2.0);
  EXPECT_EQ(check_strap_against_elbow(imu, imu + Vec3(0.08, 0.0, 0.03)), VisualRejection::kNone);  // the SDK's bias
  // The other arm's strap 20 cm further along the segment.
  EXPECT_EQ(check_strap_against_elbow(imu + Vec3(0.2, 0.0, 0.0), imu), VisualRejection::kStrapFarFromElbow);
  OcclusionTestOptions loose;
  loose.max_elbow_disagreement_m = 0.25;
  EXPECT_EQ(check_strap_against_elbow(imu + Vec3(0.2, 0.0, 0.0), imu, loose), VisualRejection::kNone);
  EXPECT_EQ(check_strap_against_elbow(Vec3::Constant(NAN), imu), VisualRejection::kDegenerate);
  EXPECT_STREQ(visual_rejection_name(VisualRejection::kStrapFarFromElbow), "strap far from the SDK elbow's estimate");
}

TEST(OcclusionTests, StrapWhoseElbowJumpsIsRejected) {
  const Vec3 elbow(0.3, 0.4, 2.4);
  const std::int64_t t0 = 15'500'000, one_frame = 33'333;
  // Allowed: 4 cm + 2 m/s * dt, so 10.7 cm one frame later.
  EXPECT_EQ(check_strap_continuity(elbow + Vec3(0.0, -0.10, 0.0), t0 + one_frame, elbow, t0), VisualRejection::kNone);
  // A band on the sleeve 18 cm up the arm, one frame after a good strap (posefuse-sim seed 8).
  EXPECT_EQ(check_strap_continuity(elbow + Vec3(0.14, -0.12, 0.05), t0 + one_frame, elbow, t0),
            VisualRejection::kStrapJumped);
  // Two frames: 17.3 cm allowed.
  EXPECT_EQ(check_strap_continuity(elbow + Vec3(0.0, -0.17, 0.0), t0 + 2 * one_frame, elbow, t0),
            VisualRejection::kNone);
  // Older than 0.1 s: nothing to compare with.
  EXPECT_EQ(check_strap_continuity(elbow + Vec3(0.5, 0.0, 0.0), t0 + 100'001, elbow, t0), VisualRejection::kNone);
  OcclusionTestOptions strict;
  strict.max_elbow_speed_m_s = 0.5;
  EXPECT_EQ(check_strap_continuity(elbow + Vec3(0.0, -0.10, 0.0), t0 + one_frame, elbow, t0, strict),
            VisualRejection::kStrapJumped);
  EXPECT_EQ(check_strap_continuity(Vec3::Constant(NAN), t0 + one_frame, elbow, t0), VisualRejection::kDegenerate);
  EXPECT_EQ(check_strap_continuity(elbow, t0, elbow, t0), VisualRejection::kDegenerate);  // not after it
  EXPECT_STREQ(visual_rejection_name(VisualRejection::kStrapJumped),
               "strap's elbow jumped since the last visible frame");
}

TEST(OcclusionTests, StrapWithin5cmAndNearerTheWrist) {
  const Vec3 elbow(0.0, 0.0, 2.0), wrist(0.0, 0.26, 2.0);
  const Quat K_from_F = Quat::Identity();
  const Vec3 on_axis = elbow + 0.85 * (wrist - elbow);
  EXPECT_TRUE(check_visual_forearm(elbow, wrist, on_axis + Vec3(0.04, 0, 0), K_from_F).accepted());
  const VisualCheck far = check_visual_forearm(elbow, wrist, on_axis + Vec3(0.06, 0, 0), K_from_F);
  EXPECT_EQ(far.rejection, VisualRejection::kStrapOffSegment);
  EXPECT_NEAR(far.strap.distance_m, 0.06, 1e-12);
  const VisualCheck near_elbow = check_visual_forearm(elbow, wrist, elbow + 0.4 * (wrist - elbow), K_from_F);
  EXPECT_EQ(near_elbow.rejection, VisualRejection::kStrapNearerElbow);
  // Beyond the wrist end: distance to the segment, not to the line.
  const VisualCheck beyond = check_visual_forearm(elbow, wrist, wrist + Vec3(0, 0.06, 0), K_from_F);
  EXPECT_EQ(beyond.rejection, VisualRejection::kStrapOffSegment);
  EXPECT_EQ(check_visual_forearm(elbow, elbow, on_axis, K_from_F).rejection, VisualRejection::kDegenerate);
  EXPECT_EQ(check_visual_forearm(elbow, wrist, Vec3::Constant(NAN), K_from_F).rejection, VisualRejection::kDegenerate);
}

}  // namespace
}  // namespace posefuse::forearm
