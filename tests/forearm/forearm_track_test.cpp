// ForearmTrack's per-sample uncertainty, its pronation without a calibration pose, and its offline
// solution.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "forearm/forearm_track.hpp"
#include "forearm/orientation_uncertainty.hpp"
#include "geometry/quaternion.hpp"

namespace posefuse::forearm {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

Quat about_z(double rad) { return Quat(Eigen::AngleAxisd(rad, Vec3::UnitZ())); }

// n samples 10 ms apart from t0, the IMU turning slowly about K's z.
void add_samples(ForearmTrack& track, std::int64_t t0_us, int n) {
  std::vector<std::int64_t> t_us;
  std::vector<Quat> W_from_A;
  std::vector<Vec3> force;
  for (int i = 0; i < n; ++i) {
    t_us.push_back(t0_us + 10'000 * i);
    W_from_A.push_back(about_z(0.01 * (t0_us / 10'000 + i)));
    force.push_back(Vec3(0, 0, kGravity));
  }
  track.add_imu(t_us, W_from_A, force);
}

TEST(ForearmTrack, WithoutACalibrationPoseThePronationIsNaN) {
  ForearmTrack track(Side::kRight, ForearmModel{}, false, Quat::Identity(), std::nullopt, 20.0 * kDeg);
  add_samples(track, 0, 10);
  ArmFrame frame;
  frame.t_us = 45'000;
  track.add_frame(frame);
  const ForearmTrackOutput out = track.process(true);
  ASSERT_EQ(out.samples.size(), 10u);
  for (const SettledArmSample& s : out.samples) {
    EXPECT_TRUE(std::isnan(s.pronation_rad));
    EXPECT_DOUBLE_EQ(s.orientation_rms_rad, 20.0 * kDeg);
  }
  ASSERT_EQ(out.frames.size(), 1u);
  EXPECT_TRUE(std::isnan(out.frames[0].pronation_rad));
  // K_from_A at the frame: halfway between the samples at 40 and 50 ms.
  EXPECT_LT(geometry::angle_between(out.frames[0].K_from_A, about_z(0.045)), 1e-9);
}

TEST(ForearmTrack, ARefinedMountingAppliesToLaterSamplesWithItsUncertainty) {
  ForearmTrack track(Side::kLeft, ForearmModel{}, false, Quat::Identity(), Quat::Identity(), 20.0 * kDeg);
  add_samples(track, 0, 5);
  const Quat F_from_A = Quat(Eigen::AngleAxisd(0.3, Vec3::UnitY()));
  track.set_mounting(F_from_A, 4.0 * kDeg);
  add_samples(track, 50'000, 5);
  ArmFrame between;  // the frame between the two mountings takes the larger uncertainty
  between.t_us = 45'000;
  track.add_frame(between);
  const ForearmTrackOutput out = track.process(true);
  ASSERT_EQ(out.samples.size(), 10u);
  for (std::size_t i = 0; i < out.samples.size(); ++i) {
    const SettledArmSample& s = out.samples[i];
    const bool refined = i >= 5;
    EXPECT_DOUBLE_EQ(s.orientation_rms_rad, (refined ? 4.0 : 20.0) * kDeg) << i;
    const Quat expected = (s.sample.K_from_A * (refined ? F_from_A.conjugate() : Quat::Identity())).normalized();
    EXPECT_LT(geometry::angle_between(s.K_from_F, expected), 1e-9) << i;
    EXPECT_TRUE(std::isfinite(s.pronation_rad));
  }
  ASSERT_EQ(out.frames.size(), 1u);
  EXPECT_DOUBLE_EQ(out.frames[0].orientation_rms_rad, 20.0 * kDeg);
}

TEST(ForearmTrack, TheOrientationFiltersOwnUncertaintyAddsToTheMountings) {
  // The filter lost samples before the third: it predicts 30 degrees beyond its steady error
  // there, then less. Each sample's uncertainty is the mounting's and the filter's together.
  ForearmTrack track(Side::kRight, ForearmModel{}, false, Quat::Identity(), Quat::Identity(), 4.0 * kDeg);
  const std::vector<double> filter_deg = {0.0, 0.0, 30.0, 10.0, 0.0};
  std::vector<std::int64_t> t_us;
  std::vector<Quat> W_from_A;
  std::vector<Vec3> force;
  std::vector<double> filter_rad;
  for (std::size_t i = 0; i < filter_deg.size(); ++i) {
    t_us.push_back(10'000 * static_cast<std::int64_t>(i));
    W_from_A.push_back(about_z(0.01 * static_cast<double>(i)));
    force.push_back(Vec3(0, 0, kGravity));
    filter_rad.push_back(filter_deg[i] * kDeg);
  }
  track.add_imu(t_us, W_from_A, force, filter_rad);
  const ForearmTrackOutput out = track.process(true);
  ASSERT_EQ(out.samples.size(), filter_deg.size());
  for (std::size_t i = 0; i < filter_deg.size(); ++i) {
    EXPECT_NEAR(out.samples[i].orientation_rms_rad, std::hypot(4.0, filter_deg[i]) * kDeg, 1e-12) << i;
    // The body fit's gate: y_F's alone, the mounting's error taken as isotropic, no filter's.
    EXPECT_NEAR(out.samples[i].axis_rms_rad, kDirectionRmsOverOrientationRms * 4.0 * kDeg, 1e-15) << i;
  }
  EXPECT_LT(confidence_from_rms_rad(out.samples[2].orientation_rms_rad), 0.01);
  EXPECT_GT(confidence_from_rms_rad(out.samples[4].orientation_rms_rad), 0.5);
}

// Ten samples, the mounting replaced by one turned `turn_rad` at 50 ms; frames every 10 ms
// from 5 ms. Returns the tracked frames.
std::vector<TrackedArmFrame> frames_across_a_mounting_change(ForearmTrack& track, double turn_rad,
                                                             double rms_after_rad) {
  add_samples(track, 0, 5);
  track.set_mounting(Quat(Eigen::AngleAxisd(turn_rad, Vec3::UnitX())), rms_after_rad);
  add_samples(track, 50'000, 5);
  for (std::int64_t t = 5'000; t < 90'000; t += 10'000) {
    ArmFrame frame;
    frame.t_us = t;
    track.add_frame(frame);
  }
  return track.process(true).frames;
}

TEST(ForearmTrack, AConfidentOrientationThatStepsIsFlaggedAndNotConfident) {
  ForearmTrack track(Side::kRight, ForearmModel{}, false, Quat::Identity(), Quat::Identity(), 4.0 * kDeg);
  const std::vector<TrackedArmFrame> frames = frames_across_a_mounting_change(track, 30.0 * kDeg, 4.0 * kDeg);
  ASSERT_EQ(frames.size(), 9u);
  // The frame at 45 ms lies between the last old and the first new sample: the 30 degrees come
  // in two halves, at 45 and at 55 ms, each beyond 1.944 x 4 degrees.
  EXPECT_EQ(track.orientation_steps(), 2u);
  for (const TrackedArmFrame& f : frames) {
    const bool step = f.frame.t_us == 45'000 || f.frame.t_us == 55'000;
    EXPECT_EQ(f.orientation_step_rad > 0.0, step) << f.frame.t_us;
    if (step) {
      EXPECT_NEAR(f.orientation_step_rad, 15.0 * kDeg, 0.5 * kDeg) << f.frame.t_us;
      EXPECT_GE(f.orientation_rms_rad, f.orientation_step_rad);
      EXPECT_LT(confidence_from_rms_rad(f.orientation_rms_rad), 0.5);
    }
  }
  EXPECT_NEAR(track.largest_orientation_step_rad(), 15.0 * kDeg, 0.5 * kDeg);
}

TEST(ForearmTrack, AnUncertainMountingGivingWayToABetterOneIsNoStep) {
  // 30 degrees of uncertainty before: a 20 degree change is within what it allows.
  ForearmTrack track(Side::kRight, ForearmModel{}, false, Quat::Identity(), Quat::Identity(), 30.0 * kDeg);
  const std::vector<TrackedArmFrame> frames = frames_across_a_mounting_change(track, 20.0 * kDeg, 4.0 * kDeg);
  ASSERT_EQ(frames.size(), 9u);
  EXPECT_EQ(track.orientation_steps(), 0u);
  for (const TrackedArmFrame& f : frames) EXPECT_EQ(f.orientation_step_rad, 0.0) << f.frame.t_us;
}

TEST(ForearmTrack, APronationReferenceFoundLaterAppliesFromItsSample) {
  ForearmTrack track(Side::kRight, ForearmModel{}, false, Quat::Identity(), std::nullopt, 20.0 * kDeg);
  add_samples(track, 0, 5);
  track.set_pronation_reference(Quat::Identity());
  add_samples(track, 50'000, 5);
  ArmFrame before, after;
  before.t_us = 25'000;
  after.t_us = 75'000;
  track.add_frame(before);
  track.add_frame(after);
  const ForearmTrackOutput out = track.process(true);
  ASSERT_EQ(out.samples.size(), 10u);
  for (std::size_t i = 0; i < out.samples.size(); ++i) EXPECT_EQ(std::isnan(out.samples[i].pronation_rad), i < 5) << i;
  ASSERT_EQ(out.frames.size(), 2u);
  EXPECT_TRUE(std::isnan(out.frames[0].pronation_rad));
  // Turned about K's z (= F's z here) only: no twist about y, so no pronation.
  EXPECT_NEAR(out.frames[1].pronation_rad, 0.0, 1e-9);
}

TEST(ForearmTrack, TheCamerasForearmAxisRaisesTheUncertaintyOfTheSamplesAfterIt) {
  // The IMU says the forearm's y is K's y; the camera's depth axis, at 35 ms, is 30 degrees off.
  ForearmTrack track(Side::kRight, ForearmModel{}, false, Quat::Identity(), Quat::Identity(), 2.0 * kDeg);
  std::vector<std::int64_t> t_us;
  std::vector<Quat> W_from_A;
  std::vector<Vec3> force;
  for (int i = 0; i < 10; ++i) {
    t_us.push_back(10'000 * i);
    W_from_A.push_back(Quat::Identity());
    force.push_back(Vec3(0, kGravity, 0));
  }
  track.add_imu(t_us, W_from_A, force);
  ArmFrame seen;
  seen.t_us = 35'000;
  seen.axis_from_depth = true;
  seen.forearm_tracked = true;
  seen.elbow_K = Vec3(0, 0, 2);
  seen.wrist_K = seen.elbow_K + 0.25 * Vec3(std::sin(30 * kDeg), std::cos(30 * kDeg), 0);
  track.add_frame(seen);
  const ForearmTrackOutput out = track.process(true);
  ASSERT_EQ(out.samples.size(), 10u);
  const double observed = 30 * kDeg / std::sqrt(2.0 / 3.0);
  for (std::size_t i = 0; i < out.samples.size(); ++i) {
    EXPECT_NEAR(out.samples[i].orientation_rms_rad, i < 4 ? 2.0 * kDeg : observed, 1e-9) << i;
    EXPECT_NEAR(out.samples[i].axis_rms_rad, kDirectionRmsOverOrientationRms * 2.0 * kDeg, 1e-15) << i;
  }
  ASSERT_EQ(out.frames.size(), 1u);
  EXPECT_NEAR(out.frames[0].orientation_rms_rad, observed, 1e-9);
  EXPECT_LT(confidence_from_rms_rad(observed), 0.01);
}

TEST(ForearmTrack, TheOfflineSolutionGivesEverySampleTheFinalMountingAndReference) {
  // A mounting from motion (no reference, 30 degrees), refined at 50 ms, then a calibration pose
  // found at 100 ms: live, the first samples keep the old mounting and no pronation; offline,
  // every sample has the pose's mounting, its uncertainty (and before the pose the IMU's at both
  // times) and the angle relative to it.
  ForearmTrack track(Side::kRight, ForearmModel{}, false, Quat::Identity(), std::nullopt, 30.0 * kDeg);
  EXPECT_FALSE(track.mounting_changed());
  add_samples(track, 0, 5);
  track.set_mounting(Quat(Eigen::AngleAxisd(0.2, Vec3::UnitY())), 12.0 * kDeg);
  add_samples(track, 50'000, 5);
  const Quat pose_F_from_A = Quat(Eigen::AngleAxisd(0.3, Vec3::UnitY()));
  const Quat reference = Quat(Eigen::AngleAxisd(0.1, Vec3::UnitX()));
  track.set_mounting(pose_F_from_A, 5.0 * kDeg);
  track.set_pronation_reference(reference);
  add_samples(track, 100'000, 5);
  EXPECT_TRUE(track.mounting_changed());
  const ForearmTrackOutput live = track.process(true);
  ASSERT_EQ(live.samples.size(), 15u);
  EXPECT_TRUE(std::isnan(live.samples[0].pronation_rad));

  const std::vector<SettledArmSample> offline = track.offline_samples();
  ASSERT_EQ(offline.size(), live.samples.size());
  for (std::size_t i = 0; i < offline.size(); ++i) {
    const SettledArmSample& s = offline[i];
    EXPECT_EQ(s.sample.t_us, live.samples[i].sample.t_us) << i;
    const Quat expected = (live.samples[i].sample.K_from_A * pose_F_from_A.conjugate()).normalized();
    EXPECT_LT(geometry::angle_between(s.K_from_F, expected), 1e-9) << i;
    EXPECT_NEAR(s.pronation_rad, pronation_angle(reference, expected, Side::kRight), 1e-9) << i;
    // Before the pose, the filter's steady error at the hold and at the sample's own time too.
    const double before_pose_rad = std::sqrt(25.0 * kDeg * kDeg + 2.0 * kFilterRmsRad * kFilterRmsRad);
    EXPECT_NEAR(s.orientation_rms_rad, i < 10 ? before_pose_rad : 5.0 * kDeg, 1e-12) << i;
    EXPECT_NEAR(s.axis_rms_rad, kDirectionRmsOverOrientationRms * 5.0 * kDeg, 1e-15) << i;
  }
}

TEST(ForearmTrack, TheOfflineSolutionKeepsTheFiltersUncertaintyAndChecksItAgainstTheCamera) {
  // Mounting refined from 30 to 2 degrees at 50 ms; the filter lost samples before the ninth;
  // depth axes at 35 ms (30 degrees off the final mounting's y) and at 65 ms (on it). Offline,
  // every sample has the final mounting's and the filter's uncertainty together, at least what
  // the frames on either side of it showed: the one after a sample counts too.
  ForearmTrack track(Side::kRight, ForearmModel{}, false, Quat::Identity(), std::nullopt, 30.0 * kDeg);
  std::vector<std::int64_t> t_us;
  std::vector<Quat> W_from_A;
  std::vector<Vec3> force;
  std::vector<double> filter_rad;
  for (int i = 0; i < 10; ++i) {
    t_us.push_back(10'000 * i);
    W_from_A.push_back(Quat::Identity());
    force.push_back(Vec3(0, kGravity, 0));
    filter_rad.push_back(i == 8 ? 20.0 * kDeg : 0.0);
  }
  const auto first = [](const auto& v, int n) { return std::vector(v.begin(), v.begin() + n); };
  const auto rest = [](const auto& v, int n) { return std::vector(v.begin() + n, v.end()); };
  track.add_imu(first(t_us, 5), first(W_from_A, 5), first(force, 5), first(filter_rad, 5));
  track.set_mounting(Quat::Identity(), 2.0 * kDeg);
  track.add_imu(rest(t_us, 5), rest(W_from_A, 5), rest(force, 5), rest(filter_rad, 5));
  for (const auto& [t, off_rad] : {std::pair{35'000, 30 * kDeg}, std::pair{65'000, 0.0}}) {
    ArmFrame seen;
    seen.t_us = t;
    seen.axis_from_depth = true;
    seen.forearm_tracked = true;
    seen.elbow_K = Vec3(0, 0, 2);
    seen.wrist_K = seen.elbow_K + 0.25 * Vec3(std::sin(off_rad), std::cos(off_rad), 0);
    track.add_frame(seen);
  }
  track.process(true);
  const std::vector<SettledArmSample> offline = track.offline_samples();
  ASSERT_EQ(offline.size(), 10u);
  const double observed = 30 * kDeg / std::sqrt(2.0 / 3.0);
  for (std::size_t i = 0; i < offline.size(); ++i) {
    const double expected = i <= 6 ? observed : i == 8 ? std::hypot(2.0, 20.0) * kDeg : 2.0 * kDeg;
    EXPECT_NEAR(offline[i].orientation_rms_rad, expected, 1e-9) << i;
    EXPECT_TRUE(std::isnan(offline[i].pronation_rad)) << i;
  }
}

TEST(ForearmTrack, TheOfflineSolutionOfAnUnchangedMountingIsTheLiveOne) {
  ForearmTrack track(Side::kLeft, ForearmModel{}, false, Quat::Identity(), Quat::Identity(), 4.0 * kDeg);
  add_samples(track, 0, 10);
  const ForearmTrackOutput live = track.process(true);
  const std::vector<SettledArmSample> offline = track.offline_samples();
  ASSERT_EQ(offline.size(), live.samples.size());
  for (std::size_t i = 0; i < offline.size(); ++i) {
    EXPECT_EQ(offline[i].sample.t_us, live.samples[i].sample.t_us);
    EXPECT_EQ(offline[i].K_from_F.coeffs(), live.samples[i].K_from_F.coeffs());
    EXPECT_EQ(offline[i].pronation_rad, live.samples[i].pronation_rad);
    EXPECT_EQ(offline[i].orientation_rms_rad, live.samples[i].orientation_rms_rad);
  }
}

}  // namespace
}  // namespace posefuse::forearm
