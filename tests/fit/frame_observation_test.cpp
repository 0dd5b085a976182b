#include "fit/frame_observation.hpp"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "synthetic_frames.hpp"

namespace posefuse::fit {
namespace {

struct TestFrame {
  DepthFrame frame;
  KinectSkeleton skeleton_K;
};

// Frames of different silhouette boxes, each reusing the buffers of the one before: a figure,
// the figure nearer (a larger box), one without legs far away (a smaller box inside the others),
// a plane over the whole image, then the first figure again.
std::vector<TestFrame> frame_sequence(const raycast::DepthCamera& camera) {
  std::vector<TestFrame> frames;
  for (const auto& [depth_m, legs] : {std::pair{2.5, true}, {1.8, true}, {3.5, false}})
    frames.push_back({testing::render_stick_figure(camera, testing::t_pose_skeleton(depth_m), legs),
                      testing::t_pose_skeleton(depth_m)});
  frames.push_back({testing::render_plane(camera, {0, 0, 2}, Eigen::Vector3d(0.2, 0.1, -1).normalized()),
                    testing::t_pose_skeleton(2.0)});
  frames.push_back(frames.front());
  return frames;
}

TEST(FitFrameObservation, ReusedBuffersGiveTheObservationOfFreshOnes) {
  // Everything the fitter reads (samples, normals, D_2D's arrays and border pixels, D_3D's grid
  // and answers) and the point cloud are those of a fresh computation, whatever frame came before.
  const raycast::DepthCamera camera{raycast::DepthIntrinsics{}};
  const FitOptions options;
  ObservationBuffers buffers;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  int index = 0;
  for (const TestFrame& f : frame_sequence(camera)) {
    SCOPED_TRACE("frame " + std::to_string(index++));
    const FrameObservation fresh = prepare_observation(f.frame, camera, f.skeleton_K, options);
    const FrameObservation& reused = prepare_observation(buffers, f.frame, camera, f.skeleton_K, options);
    EXPECT_EQ(reused.points_K, fresh.points_K);
    EXPECT_EQ(reused.normals_K, fresh.normals_K);
    EXPECT_EQ(reused.silhouette.distance_px, fresh.silhouette.distance_px);
    EXPECT_EQ(reused.silhouette.closest_pixel, fresh.silhouette.closest_pixel);
    EXPECT_EQ(reused.silhouette.border_pixels, fresh.silhouette.border_pixels);
    const PixelRect& a = reused.silhouette.region;
    const PixelRect& b = fresh.silhouette.region;
    EXPECT_TRUE(a.col0 == b.col0 && a.row0 == b.row0 && a.col1 == b.col1 && a.row1 == b.row1);
    const PointCloud cloud = build_point_cloud(f.frame, camera);
    EXPECT_EQ(buffers.cloud.count, cloud.count);
    EXPECT_EQ(buffers.cloud.valid, cloud.valid);
    EXPECT_EQ(buffers.cloud.value_K, cloud.value_K);
    ASSERT_TRUE(reused.behind && fresh.behind);
    EXPECT_EQ(reused.behind->grid_size(), fresh.behind->grid_size());
    EXPECT_EQ(reused.behind->grid_origin_K(), fresh.behind->grid_origin_K());
    // Points around the cloud, in front of and behind it, and some far off it (whose search
    // reads the min-depth pyramid far from the silhouette).
    for (int k = 0; k < 400; ++k) {
      const Eigen::Vector3d p = reused.points_K[static_cast<size_t>(k) % reused.points_K.size()] +
                                Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng)) * (k % 4 == 0 ? 0.8 : 0.1);
      ASSERT_EQ(reused.behind->is_behind(p), fresh.behind->is_behind(p)) << "point " << p.transpose();
      ASSERT_EQ(reused.behind->closest_behind(p), fresh.behind->closest_behind(p)) << "point " << p.transpose();
    }
  }
}

}  // namespace
}  // namespace posefuse::fit
