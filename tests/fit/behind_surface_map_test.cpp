#include "fit/behind_surface_map.hpp"

#include <gtest/gtest.h>

#include <limits>

#include "synthetic_frames.hpp"

namespace posefuse::fit {
namespace {

// A step: the left half of the image (x > 0 in K) sees a wall at 1.0 m, the right half at 1.5 m.
DepthFrame render_step(const raycast::DepthCamera& camera) {
  return testing::render_frame(camera, [](const Eigen::Vector3d& ray) -> std::optional<double> {
    return ray.x() > 0 ? 1.0 : 1.5;
  });
}

TEST(FitBehindSurface, StepSemantics) {
  const raycast::DepthCamera camera{testing::small_intrinsics(128, 106)};
  const BehindSurfaceMap map(render_step(camera), camera);
  const double voxel = map.voxel_size_m();

  // In front of the near wall: not behind; D_3D pushes straight back onto the wall.
  const Eigen::Vector3d floating_near(0.2, 0.0, 0.8);
  EXPECT_FALSE(map.is_behind(floating_near));
  const Eigen::Vector3d pushed = map.closest_behind(floating_near);
  EXPECT_TRUE(map.is_behind(pushed));
  EXPECT_NEAR(pushed.z(), 1.0, voxel);
  EXPECT_NEAR(pushed.x(), 0.2, voxel);
  EXPECT_NEAR(pushed.y(), 0.0, voxel);

  // Behind the near wall: identity.
  const Eigen::Vector3d behind(0.2, 0.1, 1.2);
  EXPECT_TRUE(map.is_behind(behind));
  EXPECT_EQ(map.closest_behind(behind), behind);

  // In front of the far wall, close to the step: the near wall's volume is closer sideways.
  const Eigen::Vector3d near_step(-0.04, 0.0, 1.2);
  EXPECT_FALSE(map.is_behind(near_step));
  const Eigen::Vector3d sideways = map.closest_behind(near_step);
  EXPECT_GT(sideways.x(), 0.0);
  EXPECT_LT((sideways - near_step).norm(), 0.04 + voxel);

  // In front of the far wall, far from the step: pushed back onto the far wall.
  const Eigen::Vector3d far_floating(-0.4, 0.0, 1.2);
  const Eigen::Vector3d back = map.closest_behind(far_floating);
  EXPECT_NEAR(back.z(), 1.5, voxel);
  EXPECT_NEAR(back.x(), -0.4, voxel);
}

TEST(FitBehindSurface, OutsideTheSilhouetteIsNeverBehind) {
  const raycast::DepthCamera camera{testing::small_intrinsics(64, 53)};
  const Eigen::Vector3d centre(0, 0, 1.5);
  const BehindSurfaceMap map(testing::render_sphere(camera, centre, 0.3), camera);
  // Far behind the sphere but beside it: the ray misses the silhouette.
  const Eigen::Vector3d beside(0.5, 0, 2.0);
  EXPECT_FALSE(map.is_behind(beside));
  const Eigen::Vector3d d3d = map.closest_behind(beside);
  EXPECT_TRUE(map.is_behind(d3d));
  EXPECT_LT(d3d.x(), 0.5);
  // Points beyond the grid are clamped into it and still get a behind point.
  EXPECT_TRUE(map.is_behind(map.closest_behind({0, 0, -50})));
  EXPECT_TRUE(map.is_behind(map.closest_behind({1e30, 0, 1})));
}

TEST(FitBehindSurface, NearestBehindVoxelEqualsBruteForce) {
  const raycast::DepthCamera camera{testing::small_intrinsics(64, 53)};
  BehindSurfaceParams params;
  params.voxel_size_m = 0.04;  // keeps the brute force small
  const BehindSurfaceMap map(testing::render_sphere(camera, {0.05, 0.02, 1.2}, 0.3), camera, params);
  const Eigen::Vector3i n = map.grid_size();
  std::vector<Eigen::Vector3d> behind;
  for (int k = 0; k < n.z(); ++k)
    for (int j = 0; j < n.y(); ++j)
      for (int i = 0; i < n.x(); ++i)
        if (map.voxel_is_behind(i, j, k)) behind.push_back(map.voxel_centre_K(i, j, k));
  ASSERT_GT(behind.size(), 100u);
  int checked = 0;
  for (int k = 0; k < n.z(); k += 3)
    for (int j = 0; j < n.y(); j += 3)
      for (int i = 0; i < n.x(); i += 3) {
        const Eigen::Vector3d c = map.voxel_centre_K(i, j, k);
        double best = std::numeric_limits<double>::infinity();
        for (const auto& b : behind) best = std::min(best, (b - c).norm());
        ASSERT_NEAR((map.closest_behind(c) - c).norm(), best, 1e-9) << i << " " << j << " " << k;
        ++checked;
      }
  EXPECT_GT(checked, 200);
}

TEST(FitBehindSurface, BadInputNamesTheField) {
  const raycast::DepthCamera camera{testing::small_intrinsics(32, 26)};
  const DepthFrame frame = testing::render_sphere(camera, {0, 0, 1}, 0.3);
  BehindSurfaceParams params;
  params.voxel_size_m = 0;
  EXPECT_EQ(testing::error_field([&] { BehindSurfaceMap(frame, camera, params); }), "behind_params.voxel_size_m");
  params = {};
  params.margin_m = std::nan("");
  EXPECT_EQ(testing::error_field([&] { BehindSurfaceMap(frame, camera, params); }), "behind_params.margin_m");
  params = {};
  params.max_voxels = 1000;
  EXPECT_EQ(testing::error_field([&] { BehindSurfaceMap(frame, camera, params); }), "behind_params.max_voxels");
  DepthFrame empty = frame;
  std::fill(empty.body_index.begin(), empty.body_index.end(), kNoBody);
  EXPECT_EQ(testing::error_field([&] { BehindSurfaceMap(empty, camera); }), "frame.body_index");
  DepthFrame short_frame = frame;
  short_frame.depth_mm.resize(3);
  EXPECT_EQ(testing::error_field([&] { BehindSurfaceMap(short_frame, camera); }), "frame.depth_mm");
  const BehindSurfaceMap map(frame, camera);
  EXPECT_EQ(testing::error_field([&] { map.closest_behind({std::nan(""), 0, 1}); }), "p_K");
}

}  // namespace
}  // namespace posefuse::fit
