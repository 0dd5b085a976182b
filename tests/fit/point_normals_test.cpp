#include "fit/point_normals.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "synthetic_frames.hpp"

namespace posefuse::fit {
namespace {

double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180 / M_PI;
}

TEST(FitNormals, TiltedPlaneNormalsMatchTruthAndFaceTheCamera) {
  const raycast::DepthCamera camera{raycast::DepthIntrinsics{}};
  const Eigen::Vector3d point(0, 0, 1.5), normal = Eigen::Vector3d(0.3, 0.2, -1).normalized();
  const PointCloud cloud = build_point_cloud(testing::render_plane(camera, point, normal), camera);
  const NormalMap normals = estimate_normals(cloud);
  EXPECT_EQ(normals.count, cloud.count);
  double worst = 0, sum = 0;
  for (int row = 0; row < camera.height(); ++row)
    for (int col = 0; col < camera.width(); ++col) {
      ASSERT_TRUE(normals.has(col, row));
      const double a = angle_deg(normals.at(col, row).cast<double>(), normal);
      worst = std::max(worst, a);
      sum += a;
    }
  EXPECT_LT(sum / cloud.count, 0.5);
  EXPECT_LT(worst, 3.0);
}

TEST(FitNormals, SphereNormalsMatchTruthAwayFromTheRim) {
  const raycast::DepthCamera camera{raycast::DepthIntrinsics{}};
  const Eigen::Vector3d centre(0.1, -0.05, 1.2);
  const double radius = 0.25;
  const PointCloud cloud = build_point_cloud(testing::render_sphere(camera, centre, radius), camera);
  const NormalMap normals = estimate_normals(cloud);
  int checked = 0;
  double worst = 0, sum = 0;
  for (int row = 0; row < camera.height(); ++row)
    for (int col = 0; col < camera.width(); ++col) {
      if (!cloud.has(col, row)) continue;
      const Eigen::Vector3d p = cloud.at(col, row).cast<double>(), truth = (p - centre).normalized();
      // Near the rim the surface is seen edge-on and the 5 px window spans a strongly curved
      // patch; check where the surface faces the camera within 60 degrees.
      if (angle_deg(truth, -p) > 60) continue;
      ASSERT_TRUE(normals.has(col, row));
      const double a = angle_deg(normals.at(col, row).cast<double>(), truth);
      worst = std::max(worst, a);
      sum += a;
      ++checked;
    }
  ASSERT_GT(checked, 5000);
  EXPECT_LT(sum / checked, 1.0);
  EXPECT_LT(worst, 3.0);
}

TEST(FitNormals, IsolatedPixelsAndFarNeighboursGiveNoNormal) {
  // Full resolution: a pixel spans about 6 mm at 2.2 m, so the patch is within 0.05 m.
  const raycast::DepthCamera camera{raycast::DepthIntrinsics{}};
  const int w = camera.width();
  DepthFrame frame = testing::render_plane(camera, {0, 0, 2}, {0, 0, -1});
  std::fill(frame.body_index.begin(), frame.body_index.end(), kNoBody);
  // A lone pixel, and a 3x3 patch whose neighbours are 0.2 m deeper except the centre.
  frame.body_index[5 * w + 5] = 0;
  for (int r = 14; r <= 16; ++r)
    for (int c = 19; c <= 21; ++c) {
      frame.body_index[r * w + c] = 0;
      if (r != 15 || c != 20) frame.depth_mm[r * w + c] = 2200;
    }
  const PointCloud cloud = build_point_cloud(frame, camera);
  const NormalMap normals = estimate_normals(cloud);
  EXPECT_FALSE(normals.has(5, 5));
  EXPECT_FALSE(normals.has(20, 15));  // its 8 neighbours are beyond 0.05 m
  EXPECT_TRUE(normals.has(19, 14));   // 8 neighbours at 2.2 m within 0.05 m
  EXPECT_FALSE(estimate_normal_at(cloud, 5, 5).has_value());
  EXPECT_TRUE(estimate_normal_at(cloud, 19, 14).has_value());
}

TEST(FitNormals, SinglePixelQueryAgreesWithTheMap) {
  const raycast::DepthCamera camera{testing::small_intrinsics(64, 53)};
  const PointCloud cloud = build_point_cloud(testing::render_sphere(camera, {0, 0, 1}, 0.3), camera);
  const NormalMap normals = estimate_normals(cloud);
  for (int row = 0; row < camera.height(); row += 3)
    for (int col = 0; col < camera.width(); col += 3) {
      const auto n = estimate_normal_at(cloud, col, row);
      ASSERT_EQ(n.has_value(), normals.has(col, row));
      if (n) {
        EXPECT_TRUE(n->isApprox(normals.at(col, row)));
      }
    }
}

TEST(FitNormals, SampleNormalsAgreeWithTheMap) {
  const raycast::DepthCamera camera{testing::small_intrinsics(64, 53)};
  const PointCloud cloud = build_point_cloud(testing::render_sphere(camera, {0, 0, 1}, 0.3), camera);
  const NormalMap normals = estimate_normals(cloud);
  std::vector<DepthSample> samples;
  for (int row = 1; row < camera.height(); row += 4)
    for (int col = 2; col < camera.width(); col += 5)
      samples.push_back({col, row, BodyZone::kTorso, false, Eigen::Vector3f::Zero()});
  const auto sampled = estimate_sample_normals(cloud, samples);
  ASSERT_EQ(sampled.size(), samples.size());
  int with_normal = 0;
  for (size_t i = 0; i < samples.size(); ++i) {
    ASSERT_EQ(sampled[i].has_value(), normals.has(samples[i].col, samples[i].row));
    if (!sampled[i]) continue;
    EXPECT_TRUE(sampled[i]->isApprox(normals.at(samples[i].col, samples[i].row)));
    ++with_normal;
  }
  EXPECT_GT(with_normal, 20);
  samples.push_back({64, 0, BodyZone::kTorso, false, Eigen::Vector3f::Zero()});
  EXPECT_EQ(testing::error_field([&] { estimate_sample_normals(cloud, samples); }),
            "samples[" + std::to_string(samples.size() - 1) + "]");
}

TEST(FitNormals, BadParamsNameTheField) {
  const raycast::DepthCamera camera{testing::small_intrinsics(32, 24)};
  const PointCloud cloud = build_point_cloud(testing::render_plane(camera, {0, 0, 2}, {0, 0, -1}), camera);
  NormalParams params;
  params.window_radius_px = 0;
  EXPECT_EQ(testing::error_field([&] { estimate_normals(cloud, params); }), "normal_params.window_radius_px");
  params = {};
  params.max_distance_m = std::nanf("");
  EXPECT_EQ(testing::error_field([&] { estimate_normals(cloud, params); }), "normal_params.max_distance_m");
  params = {};
  params.min_neighbours = 2;
  EXPECT_EQ(testing::error_field([&] { estimate_normals(cloud, params); }), "normal_params.min_neighbours");
  EXPECT_EQ(testing::error_field([&] { estimate_normal_at(cloud, 32, 0); }), "pixel");
}

}  // namespace
}  // namespace posefuse::fit
