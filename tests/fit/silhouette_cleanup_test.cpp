#include "fit/silhouette_cleanup.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

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

TEST(FitSilhouetteCleanup, RemovesOuterRingPixelsFarFromEveryBone) {
  // A stick figure at 2 m whose outer ring (body pixels within 2 px of the background) lies
  // behind it, as the sensor's flying pixels between a body and a wall close behind it do: 0.28 m
  // behind beside the trunk, 0.15 m behind along the arms; some inner pixels read 2.28 m too. All
  // lie within the skeleton's depth range [1.7 m, 2.3 m]. With the camera, the trunk's edge pixels
  // (0.15 m from the spine, seen at 2.28 m: over 0.3 m from every bone) go; the arms' (within
  // 0.2 m of their bone) and every inner pixel stay.
  const raycast::DepthCamera camera{testing::small_intrinsics(160, 120)};
  const KinectSkeleton skeleton_K = testing::t_pose_skeleton(2.0);
  DepthFrame frame = testing::render_stick_figure(camera, skeleton_K, false);
  const int w = frame.width, h = frame.height;
  const auto is_body = [&](int col, int row) {
    return col >= 0 && col < w && row >= 0 && row < h &&
           frame.body_index[static_cast<size_t>(row) * w + col] != kNoBody;
  };
  const auto at_2m = [&](int col, int row) -> Eigen::Vector3f { return camera.pixel_ray(col, row) * 2.0f; };
  const auto is_arm = [](const Eigen::Vector3f& p) { return std::abs(p.x()) > 0.3f && std::abs(p.x()) < 0.65f; };
  std::vector<uint8_t> ring(frame.body_index.size(), 0), edge(frame.body_index.size(), 0);
  for (int row = 0; row < h; ++row)
    for (int col = 0; col < w; ++col)
      for (int dr = -2; dr <= 2; ++dr)
        for (int dc = -2; dc <= 2; ++dc)
          if (is_body(col, row) && !is_body(col + dc, row + dr)) {
            ring[static_cast<size_t>(row) * w + col] = 1;
            if (std::abs(dr) + std::abs(dc) == 1) edge[static_cast<size_t>(row) * w + col] = 1;
          }
  int inner_moved = 0;
  for (int row = 0; row < h; ++row)
    for (int col = 0; col < w; ++col) {
      const size_t i = static_cast<size_t>(row) * w + col;
      if (!is_body(col, row)) continue;
      if (ring[i]) {
        frame.depth_mm[i] = is_arm(at_2m(col, row)) ? 2150 : 2280;
      } else if (i % 7 == 0) {
        frame.depth_mm[i] = 2280;
        ++inner_moved;
      }
    }
  const TrackedSkeleton tracked = TrackedSkeleton::all_tracked(skeleton_K);
  DepthFrame without_camera = frame;
  EXPECT_EQ(remove_off_body_depth(without_camera, tracked, {.depth_margin_m = 0.3}), 0u);

  const DepthFrame before = frame;
  const std::size_t removed = remove_off_body_depth(frame, tracked, {.depth_margin_m = 0.3}, &camera);
  int trunk_edge = 0, trunk_edge_removed = 0, arm = 0, arm_removed = 0, inner_removed = 0;
  for (int row = 0; row < h; ++row)
    for (int col = 0; col < w; ++col) {
      const size_t i = static_cast<size_t>(row) * w + col;
      if (before.body_index[i] == kNoBody) continue;
      const bool gone = frame.body_index[i] == kNoBody;
      const Eigen::Vector3f p = at_2m(col, row);
      if (!ring[i]) {
        inner_removed += gone;
      } else if (edge[i] && std::abs(p.x()) > 0.135f && p.y() > 0.0f && p.y() < 0.2f) {
        ++trunk_edge;
        trunk_edge_removed += gone;
      } else if (is_arm(p)) {
        ++arm;
        arm_removed += gone;
      }
    }
  EXPECT_GT(inner_moved, 50);
  EXPECT_EQ(inner_removed, 0);
  EXPECT_GT(trunk_edge, 10);
  EXPECT_EQ(trunk_edge_removed, trunk_edge);
  EXPECT_GT(arm, 10);
  EXPECT_EQ(arm_removed, 0);
  EXPECT_GE(removed, static_cast<std::size_t>(trunk_edge));
  EXPECT_EQ(frame.depth_mm, before.depth_mm);
}

}  // namespace
}  // namespace posefuse::fit
