// One arm (arm_halves.hpp) with the axis correction (ForearmTrack::use_axis_correction,
// forearm/visual_axis_correction.hpp) on the synthetic arm (tests/forearm/synthetic_arm.hpp) whose
// IMU filter is tilted: the emitted K_from_F converges onto the truth, every IMU sample is emitted
// once, in one batch per call at most, and orientations wait for the camera frames up to their time
// (at most 1 s without frames).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "../forearm/synthetic_arm.hpp"
#include "../imu/expect_error.hpp"
#include "arm_halves.hpp"
#include "collecting_output.hpp"

namespace posefuse::session {
namespace {

using forearm::Quat;
using forearm::Vec3;
using forearm::testing::ArmMotion;
using forearm::testing::seconds;
using testing::CollectingOutput;

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr std::int64_t kImuPeriodUs = 12'500;    // 80 Hz
constexpr std::int64_t kFramePeriodUs = 33'333;  // 30 Hz

// The IMU filter's inclination error: W turned 5 deg about a horizontal axis (W's x).
Quat tilted_W_from_A(const ArmMotion& motion, double t) {
  const Quat W_tilt(Eigen::AngleAxisd(5.0 * kDeg, Vec3::UnitX()));
  return W_tilt * motion.K_from_W.conjugate() * motion.K_from_A(t);
}

forearm::ArmFrame visible_frame(const ArmMotion& motion, std::int64_t t_us, bool axis_from_depth) {
  const double t = seconds(t_us);
  forearm::ArmFrame frame;
  frame.t_us = t_us;
  frame.shoulder_K = motion.shoulder(t);
  frame.elbow_K = motion.elbow(t);  // the depth axis's ends: exact here
  frame.wrist_K = motion.wrist(t);
  frame.axis_from_depth = axis_from_depth;
  frame.shoulder_tracked = frame.forearm_tracked = true;
  frame.sdk_elbow_K = frame.elbow_K;
  frame.sdk_elbow_seen = true;
  frame.strap_K = frame.elbow_K + motion.K_from_F(t) * Vec3(0.0, motion.model.d_se_m, 0.0);
  return frame;
}

struct EmittedOrientation {
  std::int64_t t_us;
  Quat K_from_F;
};

std::vector<EmittedOrientation> orientations(const CollectingOutput& out) {
  std::vector<EmittedOrientation> all;
  for (const v1::FitResult& r : out.results) {
    if (!r.has_forearm_orientations() || r.forearm_orientations().offline()) continue;
    const v1::ForearmOrientationBatch& b = r.forearm_orientations();
    for (int i = 0; i < b.t_us_size(); ++i) {
      all.push_back(
          {b.t_us(i), Quat(b.k_from_f(4 * i), b.k_from_f(4 * i + 1), b.k_from_f(4 * i + 2), b.k_from_f(4 * i + 3))});
    }
  }
  return all;
}

// 30 s streamed as it would be live: 100 ms IMU batches, each followed by the frames up to its
// end, the tracker processing after each batch. Returns the tracker's results.
// `axis_from_depth` false: the frames' elbow and wrist are marked as the SDK's.
CollectingOutput stream_tilted_arm(bool axis_correction, double frames_stop_s = 1e9, bool axis_from_depth = true) {
  const ArmMotion motion;
  testing::ArmHalves tracker("arm_r", forearm::Side::kRight, motion.model, true, motion.K_from_W, motion.K_from_F(0.0));
  if (axis_correction) tracker.use_axis_correction({});
  CollectingOutput out;
  std::int64_t next_imu_us = 0, next_frame_us = 0;
  for (std::int64_t batch_end_us = 100'000; batch_end_us <= 30'000'000; batch_end_us += 100'000) {
    std::vector<std::int64_t> t_us;
    std::vector<Quat> W_from_A;
    std::vector<Vec3> force;
    for (; next_imu_us < batch_end_us; next_imu_us += kImuPeriodUs) {
      t_us.push_back(next_imu_us);
      W_from_A.push_back(tilted_W_from_A(motion, seconds(next_imu_us)));
      force.push_back(motion.specific_force_A(seconds(next_imu_us)));
    }
    const std::size_t results_before = out.results.size();
    tracker.add_imu(t_us, W_from_A, force, out);
    for (; next_frame_us < batch_end_us; next_frame_us += kFramePeriodUs) {
      if (seconds(next_frame_us) < frames_stop_s)
        tracker.add_frame(visible_frame(motion, next_frame_us, axis_from_depth));
    }
    tracker.process(false, out);
    // One orientation batch per batch of IMU samples at most, however many frames came with it.
    std::size_t orientation_batches = 0;
    for (std::size_t r = results_before; r < out.results.size(); ++r) {
      orientation_batches += out.results[r].has_forearm_orientations();
    }
    EXPECT_LE(orientation_batches, 1u) << "after the batch ending at " << batch_end_us;
    if (axis_correction) {
      // Nothing is emitted past the newest frame processed, or 1 s before the newest sample.
      const std::vector<EmittedOrientation> emitted = orientations(out);
      if (!emitted.empty()) {
        const std::int64_t newest_frame_us =
            std::min(next_frame_us - kFramePeriodUs, static_cast<std::int64_t>(frames_stop_s * 1e6));
        EXPECT_LE(emitted.back().t_us, std::max(newest_frame_us, t_us.back() - 1'000'000))
            << "after the batch ending at " << batch_end_us;
      }
    }
  }
  tracker.finish(out);
  if (axis_correction && frames_stop_s > 30.0 && axis_from_depth) {
    EXPECT_GT(tracker.axis_correction_frames(), 500u);
  }
  return out;
}

double error_deg(const EmittedOrientation& o) {
  return geometry::angle_between(o.K_from_F, ArmMotion().K_from_F(seconds(o.t_us))) / kDeg;
}

TEST(ForearmTrackAxisCorrection, TheImuTiltIsTakenOutOfTheEmittedOrientations) {
  const std::vector<EmittedOrientation> with = orientations(stream_tilted_arm(true));
  const std::vector<EmittedOrientation> without = orientations(stream_tilted_arm(false));
  // Every IMU sample once, in order, either way.
  ASSERT_EQ(with.size(), 2400u);
  ASSERT_EQ(without.size(), 2400u);
  for (std::size_t i = 0; i < with.size(); ++i) {
    ASSERT_EQ(with[i].t_us, static_cast<std::int64_t>(i) * kImuPeriodUs);
    ASSERT_EQ(without[i].t_us, with[i].t_us);
  }
  double last_with = 0.0, last_without = 0.0;
  for (std::size_t i = 2000; i < with.size(); ++i) {  // the last 5 s
    last_with = std::max(last_with, error_deg(with[i]));
    last_without = std::max(last_without, error_deg(without[i]));
  }
  std::printf("K_from_F max error over the last 5 s: %.3f deg without the correction, %.3f deg with it\n", last_without,
              last_with);
  EXPECT_NEAR(error_deg(with.front()), 5.0, 0.01);  // nothing seen yet
  EXPECT_GT(last_without, 4.9);
  EXPECT_LT(last_with, 0.5);
}

TEST(ForearmTrackAxisCorrection, FramesWithTheSdksJointsDoNotCorrect) {
  // Where the depth fit failed the stage keeps the SDK's elbow and wrist (biased by centimetres):
  // such frames are not used, so the tilt stays.
  const std::vector<EmittedOrientation> emitted = orientations(stream_tilted_arm(true, 1e9, false));
  ASSERT_EQ(emitted.size(), 2400u);
  EXPECT_NEAR(error_deg(emitted.back()), 5.0, 1e-6);
}

TEST(ForearmTrackAxisCorrection, WithoutFramesOrientationsWaitAtMostOneSecond) {
  // The camera stops at 5 s: the checks inside stream_tilted_arm hold the emitted orientations to
  // 1 s behind the newest IMU sample, and at the end every sample is out.
  const std::vector<EmittedOrientation> emitted = orientations(stream_tilted_arm(true, 5.0));
  ASSERT_EQ(emitted.size(), 2400u);
  EXPECT_EQ(emitted.back().t_us, 2399 * kImuPeriodUs);
}

TEST(ForearmTrackAxisCorrection, MustBeSetBeforeTheFirstSample) {
  const ArmMotion motion;
  testing::ArmHalves tracker("arm_r", forearm::Side::kRight, motion.model, true, motion.K_from_W, motion.K_from_F(0.0));
  CollectingOutput out;
  tracker.add_imu({0}, {motion.K_from_W.conjugate() * motion.K_from_A(0.0)}, {motion.specific_force_A(0.0)}, out);
  posefuse::testing::expect_error([&] { tracker.use_axis_correction({}); }, ErrorCode::kInvalidArgument,
                                  "forearm.axis_correction", "before the first IMU sample");
}

}  // namespace
}  // namespace posefuse::session
