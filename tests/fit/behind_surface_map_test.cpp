#include "fit/behind_surface_map.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <optional>
#include <random>

#include "dense_behind_surface.hpp"
#include "synthetic_frames.hpp"

namespace posefuse::fit {
namespace {

// A step: the left half of the image (x > 0 in K) sees a wall at 1.0 m, the right half at 1.5 m.
DepthFrame render_step(const raycast::DepthCamera& camera) {
  return testing::render_frame(
      camera, [](const Eigen::Vector3d& ray) -> std::optional<double> { return ray.x() > 0 ? 1.0 : 1.5; });
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

// A random scene: a few spheres in front of an optional tilted back plane, millimetre noise
// and pixels of the silhouette without a depth reading.
DepthFrame random_scene(const raycast::DepthCamera& camera, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  struct Sphere {
    Eigen::Vector3d centre;
    double radius;
  };
  std::vector<Sphere> spheres;
  const int count = 2 + static_cast<int>(uniform(rng) * 3);
  for (int s = 0; s < count; ++s)
    spheres.push_back(
        {{-0.5 + uniform(rng), -0.4 + 0.8 * uniform(rng), 0.9 + 1.5 * uniform(rng)}, 0.08 + 0.3 * uniform(rng)});
  const bool back_plane = uniform(rng) < 0.5;
  const Eigen::Vector3d plane_normal =
      Eigen::Vector3d(0.3 * (uniform(rng) - 0.5), 0.3 * (uniform(rng) - 0.5), -1).normalized();
  const double plane_depth = 2.6 + 0.5 * uniform(rng);
  DepthFrame frame = testing::render_frame(camera, [&](const Eigen::Vector3d& ray) -> std::optional<double> {
    std::optional<double> nearest;
    const Eigen::Vector3d dir = ray.normalized();
    for (const Sphere& s : spheres) {
      const double b = dir.dot(s.centre), c = s.centre.squaredNorm() - s.radius * s.radius;
      const double disc = b * b - c;
      if (disc < 0) continue;
      const double t = b - std::sqrt(disc);
      const double z = t * dir.z();
      if (t > 0 && (!nearest || z < *nearest)) nearest = z;
    }
    if (back_plane && !nearest) {
      const double t = plane_depth * plane_normal.z() / plane_normal.dot(ray);
      if (t > 0) nearest = t;
    }
    return nearest;
  });
  std::normal_distribution<double> noise_mm(0.0, 5.0);
  for (size_t i = 0; i < frame.depth_mm.size(); ++i) {
    if (frame.depth_mm[i] == kNoDepth) continue;
    if (uniform(rng) < 0.05) {
      frame.depth_mm[i] = kNoDepth;  // silhouette pixel without a reading
      continue;
    }
    frame.depth_mm[i] = static_cast<uint16_t>(std::max(1.0, frame.depth_mm[i] + noise_mm(rng)));
  }
  return frame;
}

// The query-time shell search returns a behind voxel exactly as near (on the grid) as the full
// distance transform of the first implementation, for points anywhere around random scenes.
TEST(FitBehindSurface, QuerySearchEqualsDenseTransformOnRandomFrames) {
  const raycast::DepthCamera camera{testing::small_intrinsics(64, 53)};
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  int compared_in_front = 0;
  for (int scene = 0; scene < 6; ++scene) {
    BehindSurfaceParams params;
    params.voxel_size_m = scene % 2 == 0 ? 0.04 : 0.05;
    const DepthFrame frame = random_scene(camera, rng);
    const BehindSurfaceMap map(frame, camera, params);
    const std::vector<double> dense = testing::dense_behind_distance2(map);
    const Eigen::Vector3i n = map.grid_size();
    const PointCloud cloud = build_point_cloud(frame, camera);
    for (int q = 0; q < 1000; ++q) {
      Eigen::Vector3d p;
      if (q % 4 == 0) {
        // Anywhere in the grid's box grown by 0.2 m (outside points are clamped into the grid).
        const Eigen::Vector3d lo = map.grid_origin_K() - Eigen::Vector3d::Constant(0.2);
        const Eigen::Vector3d extent = map.voxel_size_m() * n.cast<double>() + Eigen::Vector3d::Constant(0.4);
        p = lo + extent.cwiseProduct(Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng)));
      } else {
        // A float-like point: up to 0.15 m in front of a cloud point, a little sideways.
        size_t pixel;
        do {
          pixel = static_cast<size_t>(uniform(rng) * cloud.valid.size());
        } while (!cloud.valid[pixel]);
        p = cloud.value_K[pixel].cast<double>() +
            Eigen::Vector3d(0.04 * (uniform(rng) - 0.5), 0.04 * (uniform(rng) - 0.5), -0.15 * uniform(rng));
      }
      const Eigen::Vector3d d3d = map.closest_behind(p);
      if (map.is_behind(p)) {
        EXPECT_EQ(d3d, p);
        continue;
      }
      const Eigen::Vector3i cell = map.voxel_of(p), found = map.voxel_of(d3d);
      ASSERT_LT((map.voxel_centre_K(found.x(), found.y(), found.z()) - d3d).norm(), 1e-9);
      ASSERT_TRUE(map.voxel_is_behind(found.x(), found.y(), found.z()));
      const double d2 = (found - cell).cast<double>().squaredNorm();
      const size_t index = (static_cast<size_t>(cell.z()) * n.y() + cell.y()) * n.x() + cell.x();
      ASSERT_EQ(d2, dense[index]) << "scene " << scene << " query " << q;
      ++compared_in_front;
    }
  }
  EXPECT_GT(compared_in_front, 2000);
}

// The map keeps the frame's depth inside the silhouette (recovered from the point cloud): a
// point at a pixel's depth is behind, one half a millimetre nearer is not; pixels without a
// reading or outside the silhouette are never behind.
TEST(FitBehindSurface, KeepsTheFramesDepthExactly) {
  const raycast::DepthCamera camera{testing::small_intrinsics(64, 53)};
  std::mt19937_64 rng(11);
  for (int scene = 0; scene < 3; ++scene) {
    const DepthFrame frame = random_scene(camera, rng);
    const PointCloud cloud = build_point_cloud(frame, camera);
    const BehindSurfaceMap map(cloud, camera);
    const BehindSurfaceMap from_frame(frame, camera);
    EXPECT_EQ(map.grid_size(), from_frame.grid_size());
    EXPECT_EQ(map.grid_origin_K(), from_frame.grid_origin_K());
    int with_depth = 0;
    for (int row = 0; row < camera.height(); ++row)
      for (int col = 0; col < camera.width(); ++col) {
        const size_t i = static_cast<size_t>(row) * camera.width() + col;
        const Eigen::Vector3d ray = camera.pixel_ray(col, row).cast<double>();
        if (frame.body_index[i] == kNoBody || frame.depth_mm[i] == kNoDepth) {
          EXPECT_FALSE(map.is_behind(ray * 10.0)) << col << ", " << row;
          continue;
        }
        const double z = frame.depth_mm[i] * 1e-3;
        EXPECT_TRUE(map.is_behind(ray * z)) << col << ", " << row;
        EXPECT_FALSE(map.is_behind(ray * (z - 0.0005))) << col << ", " << row;
        ++with_depth;
      }
    EXPECT_GT(with_depth, 100);
  }
  EXPECT_EQ(testing::error_field([&] { BehindSurfaceMap(PointCloud::empty(3, 3), camera); }), "cloud.width");
}

// A cache used with a new frame's map (which may sit at the old map's address) starts afresh.
TEST(FitBehindSurface, CacheFollowsTheFrameNotTheAddress) {
  const raycast::DepthCamera camera{testing::small_intrinsics(64, 53)};
  const Eigen::Vector3d floating(0.0, 0.0, 0.7);
  BehindSurfaceCache cache;
  std::optional<BehindSurfaceMap> map;
  map.emplace(testing::render_plane(camera, {0, 0, 1.0}, {0, 0, -1}), camera);
  EXPECT_NEAR(map->closest_behind(floating, cache).z(), 1.0, map->voxel_size_m());
  map.reset();
  map.emplace(testing::render_plane(camera, {0, 0, 1.4}, {0, 0, -1}), camera);  // same storage
  EXPECT_EQ(map->closest_behind(floating, cache), map->closest_behind(floating));
  EXPECT_NEAR(map->closest_behind(floating, cache).z(), 1.4, map->voxel_size_m());
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
