#include "fit/silhouette_cleanup.hpp"

#include <gtest/gtest.h>

#include <random>

#include "synthetic_frames.hpp"

namespace posefuse::fit {
namespace {

TEST(FitSilhouetteCleanup, RemovesExactlyTheBodyPixelsOutsideTheSkeletonsDepthRange) {
  // A stick figure at 2 m with body-index noise of every run length (the background is passed over
  // 8 pixels at a time) and depth readings from 0.5 m to 4.5 m: the pixels removed are those a
  // per-pixel test of the range [1.7 m, 2.3 m] removes, and nothing else changes.
  const raycast::DepthCamera camera{testing::small_intrinsics(93, 71)};
  const KinectSkeleton skeleton_K = testing::t_pose_skeleton(2.0);
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    DepthFrame frame = testing::render_stick_figure(camera, skeleton_K, trial % 2 == 0);
    for (size_t i = 0; i < frame.body_index.size(); ++i) {
      if (rng() % 5 == 0) frame.body_index[i] = frame.body_index[i] == kNoBody ? 0 : kNoBody;
      if (rng() % 3 == 0) frame.depth_mm[i] = static_cast<uint16_t>(500 + rng() % 4000);
      if (rng() % 17 == 0) frame.depth_mm[i] = kNoDepth;
    }
    const DepthFrame before = frame;
    const TrackedSkeleton tracked = TrackedSkeleton::all_tracked(skeleton_K);
    const std::size_t removed = remove_off_body_depth(frame, tracked, {.depth_margin_m = 0.3});
    std::size_t expected_removed = 0;
    const double near_mm = 1000.0 * (2.0 - 0.3), far_mm = 1000.0 * (2.0 + 0.3);
    for (size_t i = 0; i < frame.body_index.size(); ++i) {
      const uint16_t z = before.depth_mm[i];
      const bool off_body = before.body_index[i] != kNoBody && z != kNoDepth && (z < near_mm || z > far_mm);
      expected_removed += off_body;
      ASSERT_EQ(frame.body_index[i], off_body ? kNoBody : before.body_index[i]) << "trial " << trial << " pixel " << i;
    }
    EXPECT_EQ(removed, expected_removed);
    EXPECT_GT(removed, 0u);
    EXPECT_EQ(frame.depth_mm, before.depth_mm);
  }
}

}  // namespace
}  // namespace posefuse::fit
