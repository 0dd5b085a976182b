// The forearm stage's per-arm tracker (session/stages/arm_tracker.hpp) on a synthetic arm
// (tests/forearm/synthetic_arm.hpp): how it cuts the track into gaps.
#include "session/stages/arm_tracker.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "../forearm/synthetic_arm.hpp"

namespace posefuse::session {
namespace {

using forearm::Quat;
using forearm::Vec3;
using namespace forearm::testing;

struct CollectingOutput : StageOutput {
  void emit(v1::FitResult&& result) override { results.push_back(std::move(result)); }
  void warn(const std::string& code, const std::string& field, const std::string& message) override {
    warnings.push_back(code + " " + field + ": " + message);
  }
  v1::CalibrationReport& calibration() override { return report; }
  std::vector<v1::FitResult> results;
  std::vector<std::string> warnings;
  v1::CalibrationReport report;
};

// The strap hidden for 3 s but seen at one frame in the middle (a glimpse, or a false detection
// that passes II-J): one frame cannot close the gap (its exit fit needs 2 in 500 ms), so the
// tracker recovers one gap from before the glimpse to after it, not two that neither method can,
// and the live estimate goes on after the glimpse (a new one cannot start from one sample).
TEST(ArmTracker, LoneDetectionInsideAGapDoesNotSplitIt) {
  const ArmMotion motion;
  const double gap_begin_s = 2.0, gap_end_s = 5.0, glimpse_s = 3.5, duration_s = 7.0;
  ArmTracker tracker("arm_r", forearm::Side::kRight, motion.model, true, motion.K_from_W, motion.K_from_F(0.0));
  CollectingOutput out;
  std::vector<std::int64_t> t_us;
  std::vector<Quat> W_from_A;
  std::vector<Vec3> specific_force_A;
  for (std::int64_t t = 0; seconds(t) <= duration_s; t += 12'500) {
    t_us.push_back(t);
    W_from_A.push_back(motion.K_from_W.conjugate() * motion.K_from_A(seconds(t)));
    specific_force_A.push_back(motion.specific_force_A(seconds(t)));
  }
  tracker.add_imu(t_us, W_from_A, specific_force_A, out);
  std::int64_t glimpse_us = -1;
  for (std::int64_t t = 0; seconds(t) <= duration_s; t += 33'333) {
    const double ts = seconds(t);
    ArmFrame frame;
    frame.t_us = t;
    frame.shoulder_K = motion.shoulder(ts);
    frame.elbow_K = motion.elbow(ts);
    frame.wrist_K = motion.wrist(ts);
    frame.shoulder_tracked = frame.forearm_tracked = true;
    frame.sdk_elbow_K = frame.elbow_K + Vec3(0.05, -0.03, 0.02);
    frame.sdk_elbow_seen = true;
    const bool glimpse = glimpse_us < 0 && ts >= glimpse_s;
    if (glimpse) glimpse_us = t;
    if (ts <= gap_begin_s || ts >= gap_end_s || glimpse) {
      frame.strap_K = frame.elbow_K + motion.K_from_F(ts) * Vec3(0.0, motion.model.d_se_m, 0.0);
    }
    tracker.add_frame(frame);
  }
  tracker.process(false, out);
  tracker.finish(out);

  for (const std::string& w : out.warnings) ADD_FAILURE() << w;
  std::vector<const v1::RecoveredSegment*> smoother;
  std::size_t visible_inside = 0, predicted_after_glimpse = 0;
  for (const v1::FitResult& r : out.results) {
    if (r.has_recovered_segment() && r.recovered_segment().method() == v1::RecoveredSegment::SMOOTHER) {
      smoother.push_back(&r.recovered_segment());
    }
    if (r.has_frame()) {
      for (const v1::ImuPosition& p : r.frame().imu_positions()) {
        visible_inside += p.source() == v1::VISUAL && r.frame().t_us() > 2'000'000 && r.frame().t_us() < 5'000'000;
        predicted_after_glimpse += p.source() == v1::PREDICTED && r.frame().t_us() > glimpse_us;
      }
    }
  }
  EXPECT_EQ(visible_inside, 1u);  // the glimpse itself is reported as seen (the output is causal)
  EXPECT_GE(predicted_after_glimpse, 40u);  // 1.5 s at 30 Hz
  ASSERT_EQ(smoother.size(), 1u);
  EXPECT_LE(seconds(smoother[0]->t_start_us()), gap_begin_s);
  EXPECT_GE(seconds(smoother[0]->t_end_us()), gap_end_s);
  EXPECT_GT(smoother[0]->t_start_us(), 1'900'000);
  EXPECT_LT(smoother[0]->t_end_us(), 5'100'000);
}

}  // namespace
}  // namespace posefuse::session
