// Paper 1's gap recovery (II-K, II-L) and the smoother on synthetic arms.
#include <gtest/gtest.h>

#include <algorithm>

#include "../imu/expect_error.hpp"
#include "forearm/gap_smoother.hpp"
#include "forearm/paper_recovery.hpp"
#include "synthetic_arm.hpp"

namespace posefuse::forearm {
namespace {

using namespace posefuse::forearm::testing;
using posefuse::testing::expect_error;

double gap_seconds(const GapSpan& g) { return static_cast<double>(g.t_end_us - g.t_start_us) * 1e-6; }

// A rest-to-rest move inside the gap (smooth, zero velocity and acceleration at both ends) with
// the arm at rest in both boundary windows: the 500 ms lines are exact, so the double
// integration with its drift corrections must reproduce the move up to the trapezoid rule's
// error at 80 Hz (below 0.05 mm here; we allow 0.1 mm).
TEST(PaperRecovery, ExactWhenAtRestOutsideTheGap) {
  const Vec3 rest(0.1, 0.2, 1.8), move(0.15, -0.1, 0.05);
  const double t_a = 1.0, t_b = 2.0;  // the move; the track is occluded in (0.95, 2.05)
  const double w = 2.0 * std::numbers::pi;
  auto position = [&](double t) -> Vec3 {
    const double u = std::clamp((t - t_a) / (t_b - t_a), 0.0, 1.0);
    return rest + move * (u - std::sin(w * u) / w);
  };
  auto acceleration = [&](double t) -> Vec3 {
    const double u = std::clamp((t - t_a) / (t_b - t_a), 0.0, 1.0);
    return move * (w * std::sin(w * u) / ((t_b - t_a) * (t_b - t_a)));
  };
  GapRecoveryInput in;
  in.model = ArmMotion().model;
  const Quat K_from_A = geometry::quat_from_rotation_vector(Vec3(0.3, -0.5, 0.2));
  for (std::int64_t t = 0; t <= 3'000'000; t += 33'333) {
    const double ts = seconds(t);
    in.track.push_back({t, position(ts), !(ts > 0.95 && ts < 2.05)});
    in.shoulder.push_back({t, Vec3(0.2, 0.3, 2.0)});
  }
  for (std::int64_t t = 3'000; t <= 3'000'000; t += 12'500) {
    const double ts = seconds(t);
    in.arm.push_back({t, K_from_A, K_from_A.conjugate() * (acceleration(ts) + Vec3(0, 0, kGravity))});
  }
  const RecoveredGap gap = recover_gap_paper(in, only_gap(in), {.apply_shoulder_sphere = false});
  for (std::size_t i = 0; i < gap.t_us.size(); ++i) {
    EXPECT_LT((gap.p_K[i] - position(seconds(gap.t_us[i]))).norm(), 1e-4) << gap.t_us[i];
  }
}

// II-L.3: after the snap every recovered position puts the elbow d_ul from the shoulder.
TEST(PaperRecovery, SnapsOntoTheShoulderSphere) {
  const ArmMotion motion;
  const GapRecoveryInput in = make_gap_input(motion, SensorNoise{}, 4.0, 1.2, 2.4);
  const RecoveredGap gap = recover_gap_paper(in, only_gap(in));
  const ArmTimeline arm(in);
  for (std::size_t i = 0; i < gap.t_us.size(); ++i) {
    const Vec3 centre = arm.sphere_centre_K(static_cast<double>(gap.t_us[i]));
    EXPECT_NEAR((gap.p_K[i] - centre).norm(), motion.model.d_ul_m, 1e-9);
  }
}

// Slow motion (0.1 Hz swing): the 500 ms boundary lines are nearly exact, so the paper's method
// works. Budget: line-fit bias on the curved track ~1 cm (measured 1.3 cm max noise-free for a
// 2 s gap), boundary noise 5 mm / sqrt(16) in position and ~8 mm/s in velocity (x T/4), and the
// 2-degree attitude drift leaking ~0.3 m/s^2 of gravity, half of which the linear corrections
// remove. Bound: max 5 cm, RMS 3 cm for gaps up to 2 s.
TEST(PaperRecovery, RecoversSlowMotionWithinBounds) {
  ArmMotion slow;
  slow.azimuth_hz = slow.elevation_hz = slow.forearm_hz = 0.1;
  for (double length : {0.5, 1.0, 1.5, 2.0}) {
    for (unsigned seed = 1; seed <= 3; ++seed) {
      const GapRecoveryInput in = make_gap_input(slow, {.seed = seed}, 5.0, 1.3, 1.3 + length);
      const GapErrors e = gap_errors(slow, recover_gap_paper(in, only_gap(in)));
      EXPECT_LT(e.max_m, 0.05) << length << " s, seed " << seed;
      EXPECT_LT(e.rms_m, 0.03) << length << " s, seed " << seed;
    }
  }
}

// The smoother on the fast default swing (0.5 Hz, up to ~2 m/s, ~6 m/s^2). Budget: a trajectory
// pinned at both ends by position data, driven by an acceleration error e(t), deviates by at most
// max|e| T^2 / 8. The 2-degree attitude drift leaks up to ~0.35 m/s^2 of gravity; the bias and
// linear leak terms absorb most of it, and we allow |e| <= 0.15 m/s^2 to remain; boundary noise
// adds ~1 cm. Bound: max 1 cm + 0.15 T^2 / 8, RMS 60% of that (2.4 cm RMS for a 2 s gap; the
// bench measures 1.4 cm).
TEST(GapSmoother, RecoversFastMotionWithinBounds) {
  const ArmMotion motion;
  for (double length : {0.5, 1.0, 1.5, 2.0}) {
    for (double start : {1.0, 1.3, 1.6}) {
      const GapRecoveryInput in = make_gap_input(motion, SensorNoise{}, 5.0, start, start + length);
      const GapSpan span = only_gap(in);
      const double bound = 0.01 + 0.15 * gap_seconds(span) * gap_seconds(span) / 8.0;
      const GapErrors e = gap_errors(motion, recover_gap_smoother(in, span));
      EXPECT_LT(e.max_m, bound) << length << " s from " << start;
      EXPECT_LT(e.rms_m, 0.6 * bound) << length << " s from " << start;
    }
  }
}

// Paper 1's reported failure: the arm accelerates into the gap, the 500 ms line gives the
// window's mean velocity, v0 is too small and the recovered path falls short. The smoother
// uses the accelerations inside the window too and must do much better.
TEST(GapSmoother, BeatsThePaperWhenEntryVelocityIsUnderestimated) {
  ArmMotion motion;
  motion.azimuth_amp = 1.0;
  motion.elevation_amp = 0.2;
  // Azimuth turns at t = 1.5 s and is fastest at t = 2 s: the gap starts at 1.9 s.
  const GapRecoveryInput in = make_gap_input(motion, SensorNoise{}, 5.0, 1.9, 3.1);
  const GapSpan span = only_gap(in);
  const double t0 = seconds(span.t_start_us);
  const Vec3 v_true = (motion.imu_position(t0 + 1e-4) - motion.imu_position(t0 - 1e-4)) / 2e-4;
  const BoundaryState entry = fit_boundary_line(in.track, span.t_start_us, -1, 0.5);
  ASSERT_LT(entry.v_K.norm(), 0.8 * v_true.norm());  // the scenario really underestimates v0

  const GapErrors paper = gap_errors(motion, recover_gap_paper(in, span));
  const GapErrors smoother = gap_errors(motion, recover_gap_smoother(in, span));
  EXPECT_GT(paper.max_m, 0.05);  // the failure is visible
  EXPECT_LT(smoother.rms_m, 0.3 * paper.rms_m);
  EXPECT_LT(smoother.max_m, 0.3 * paper.max_m);
}

TEST(GapRecovery, RefusesGapsWithoutBoundaryData) {
  const ArmMotion motion;
  GapRecoveryInput in = make_gap_input(motion, SensorNoise{}, 3.0, -1.0, 1.0);  // starts occluded
  expect_error([&] { recover_gap_paper(in, only_gap(in)); }, ErrorCode::kFailedPrecondition, "track.before_gap");
  expect_error([&] { recover_gap_smoother(in, only_gap(in)); }, ErrorCode::kFailedPrecondition, "track.before_gap");
  in = make_gap_input(motion, SensorNoise{}, 3.0, 2.0, 9.0);  // ends occluded
  expect_error([&] { recover_gap_paper(in, only_gap(in)); }, ErrorCode::kFailedPrecondition, "track.after_gap");
  // Only one visible sample after the gap.
  in = make_gap_input(motion, SensorNoise{}, 3.0, 1.0, 2.0);
  for (std::size_t i = 0; i < in.track.size(); ++i) {
    if (in.track[i].t_us > 2'040'000) in.track[i].visible = false;
  }
  const GapSpan first = find_gaps(in.track).at(0);
  expect_error([&] { recover_gap_paper(in, first); }, ErrorCode::kFailedPrecondition, "track.after_gap");
  // Arm samples stop inside the gap.
  in = make_gap_input(motion, SensorNoise{}, 3.0, 1.0, 2.0);
  in.arm.resize(100);  // up to ~1.24 s
  expect_error([&] { recover_gap_smoother(in, only_gap(in)); }, ErrorCode::kFailedPrecondition, "arm");
  // Bad values are named.
  in = make_gap_input(motion, SensorNoise{}, 3.0, 1.0, 2.0);
  in.shoulder[4].p_K.z() = INFINITY;
  expect_error([&] { recover_gap_smoother(in, only_gap(in)); }, ErrorCode::kInvalidArgument, "shoulder[4].p_K");
}

}  // namespace
}  // namespace posefuse::forearm
