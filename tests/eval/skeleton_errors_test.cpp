#include "eval/skeleton_errors.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "common/error.hpp"

using namespace posefuse::eval;

namespace {

// A constant 50 mm offset along x with +-10 mm alternating along y: mean (0.05, 0, 0) over an
// even number of frames, every error 10 mm from it.
std::vector<Vec3> offset_and_jitter(int frames) {
  std::vector<Vec3> e;
  for (int k = 0; k < frames; ++k) e.emplace_back(0.05, k % 2 == 0 ? 0.01 : -0.01, 0.0);
  return e;
}

}  // namespace

TEST(JointErrorStats, BiasSpreadAndMeanErrorOfAConstructedJoint) {
  const JointErrorStats s = joint_error_stats(offset_and_jitter(40), 0.1);
  EXPECT_EQ(s.frames, 40u);
  EXPECT_NEAR(s.bias_m, 0.05, 1e-12);
  EXPECT_NEAR(s.spread_m, 0.01, 1e-12);
  EXPECT_NEAR(s.mean_abs_m, std::hypot(0.05, 0.01), 1e-12);
  EXPECT_EQ(s.off_track_frames, 0u);
}

TEST(JointErrorStats, ARotatingBiasHasNoMeanButSpreadsByItsLength) {
  // 80 mm turning once around a circle over the session: the mean error vector vanishes, the
  // whole bias shows as spread and as mean |e|.
  std::vector<Vec3> e;
  const int n = 300;
  for (int k = 0; k < n; ++k) {
    const double a = 2 * EIGEN_PI * k / n;
    e.emplace_back(0.08 * std::cos(a), 0.08 * std::sin(a), 0.0);
  }
  const JointErrorStats s = joint_error_stats(e, 0.1);
  EXPECT_LT(s.bias_m, 1e-12);
  EXPECT_NEAR(s.spread_m, 0.08, 1e-12);
  EXPECT_NEAR(s.mean_abs_m, 0.08, 1e-12);
}

TEST(OffTrackFrames, SingleAndDoubleFrameJumpsAreFoundStepsAreNot) {
  std::vector<Vec3> e = offset_and_jitter(60);
  e[0] += Vec3(0.0, 0.0, 0.2);  // at the first frame (clamped window)
  e[10] += Vec3(0.15, 0.0, 0.0);
  e[30] += Vec3(0.0, -0.2, 0.1);
  e[31] += Vec3(0.0, 0.1, 0.2);   // two frames in a row, other directions
  e[59] += Vec3(-0.3, 0.0, 0.0);  // at the last frame
  // An INFERRED-like step: 100 mm more from frame 45 on, kept.
  for (int k = 45; k < 60; ++k) e[static_cast<std::size_t>(k)] += Vec3(0.0, 0.0, 0.1);
  const std::vector<bool> off = off_track_frames(e, 0.1);
  for (int k = 0; k < 60; ++k) {
    const bool expected = k == 0 || k == 10 || k == 30 || k == 31 || k == 59;
    EXPECT_EQ(off[static_cast<std::size_t>(k)], expected) << "frame " << k;
  }
  EXPECT_EQ(joint_error_stats(e, 0.1).off_track_frames, 5u);
  // A threshold above the smallest jump (150 mm) leaves it out.
  EXPECT_FALSE(off_track_frames(e, 0.16)[10]);
}

TEST(JointErrorStats, EmptyAndBadInput) {
  const JointErrorStats s = joint_error_stats({}, 0.1);
  EXPECT_EQ(s.frames, 0u);
  EXPECT_TRUE(std::isnan(s.bias_m) && std::isnan(s.spread_m) && std::isnan(s.mean_abs_m));
  EXPECT_THROW(off_track_frames(offset_and_jitter(4), 0.0), posefuse::Error);
  EXPECT_THROW(off_track_frames(offset_and_jitter(4), 0.1, 0), posefuse::Error);
  std::vector<Vec3> bad = offset_and_jitter(4);
  bad[2].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(joint_error_stats(bad, 0.1), posefuse::Error);
}
