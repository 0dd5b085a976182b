#include "fit/depth_frame.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "common/error.hpp"
#include "synthetic_frames.hpp"

namespace posefuse::fit {
namespace {

TEST(FitPointCloud, PlanePointsLieOnThePlaneAndReprojectToTheirPixel) {
  const raycast::DepthCamera camera{raycast::DepthIntrinsics{}};
  const Eigen::Vector3d point(0, 0, 1.5), normal = Eigen::Vector3d(0.3, 0.2, -1).normalized();
  const DepthFrame frame = testing::render_plane(camera, point, normal);
  const PointCloud cloud = build_point_cloud(frame, camera);
  ASSERT_EQ(cloud.count, camera.width() * camera.height());
  for (int row = 0; row < camera.height(); row += 7)
    for (int col = 0; col < camera.width(); col += 7) {
      const Eigen::Vector3d p = cloud.at(col, row).cast<double>();
      // Depth is stored to the millimetre, so the point is off the plane by at most 0.5 mm in z.
      EXPECT_LT(std::abs(normal.dot(p - point)), 0.0006);
      const auto uv = camera.project(p);
      ASSERT_TRUE(uv);
      EXPECT_NEAR(uv->x(), col, 1e-3);
      EXPECT_NEAR(uv->y(), row, 1e-3);
    }
}

TEST(FitPointCloud, KeepsOnlySilhouettePixelsWithDepth) {
  const raycast::DepthCamera camera{testing::small_intrinsics(32, 24)};
  DepthFrame frame = testing::render_plane(camera, {0, 0, 2}, {0, 0, -1});
  frame.body_index[5] = kNoBody;  // background with depth
  frame.depth_mm[6] = kNoDepth;   // body without depth
  const PointCloud cloud = build_point_cloud(frame, camera);
  EXPECT_EQ(cloud.count, 32 * 24 - 2);
  EXPECT_FALSE(cloud.valid[5]);
  EXPECT_FALSE(cloud.valid[6]);
  EXPECT_TRUE(cloud.valid[7]);
  // x left, y up: the top-left pixel sees a point to the left (x > 0) and above (y > 0).
  EXPECT_GT(cloud.at(0, 0).x(), 0);
  EXPECT_GT(cloud.at(0, 0).y(), 0);
  EXPECT_FLOAT_EQ(cloud.at(0, 0).z(), 2.0f);
}

TEST(FitPointCloud, EqualsThePerPixelUnprojectionOnASparseSilhouette) {
  // A width that is no multiple of 8 and background runs of every length (the background is
  // passed over 8 pixels at a time): the same points as unprojecting pixel by pixel.
  const raycast::DepthCamera camera{testing::small_intrinsics(53, 17)};
  DepthFrame frame = testing::render_plane(camera, {0, 0, 2}, {0.2, 0.1, -1});
  std::mt19937 rng(3);
  for (size_t i = 0; i < frame.body_index.size(); ++i) {
    if (rng() % 4 != 0) frame.body_index[i] = kNoBody;
    if (rng() % 10 == 0) frame.depth_mm[i] = kNoDepth;
  }
  const PointCloud cloud = build_point_cloud(frame, camera);
  int expected_count = 0;
  for (int row = 0; row < 17; ++row)
    for (int col = 0; col < 53; ++col) {
      const size_t i = static_cast<size_t>(row) * 53 + col;
      const bool valid = frame.body_index[i] != kNoBody && frame.depth_mm[i] != kNoDepth;
      expected_count += valid;
      ASSERT_EQ(cloud.has(col, row), valid) << "pixel " << col << ", " << row;
      if (valid) {
        EXPECT_EQ(cloud.at(col, row), (camera.pixel_ray(col, row) * (frame.depth_mm[i] * 1e-3f)).eval());
      }
    }
  EXPECT_EQ(cloud.count, expected_count);
}

TEST(FitPointCloud, BoxIsTheSmallestRectangleHoldingEveryCloudPixel) {
  // Sparse random silhouettes (often a single pixel or none with depth): the box kept while the
  // cloud is built equals the scan of every valid pixel.
  const raycast::DepthCamera camera{testing::small_intrinsics(37, 19)};
  std::mt19937 rng(5);
  for (int trial = 0; trial < 100; ++trial) {
    DepthFrame frame = testing::render_plane(camera, {0, 0, 2}, {0.1, -0.2, -1});
    const unsigned keep = 1 + rng() % 200;  // about one pixel in `keep` is body
    for (size_t i = 0; i < frame.body_index.size(); ++i)
      if (rng() % keep != 0) frame.body_index[i] = kNoBody;
    frame.body_index[rng() % frame.body_index.size()] = 0;  // never empty
    const PointCloud cloud = build_point_cloud(frame, camera);
    const PixelRect expected = occupied_box(cloud.valid, cloud.width, cloud.height);
    EXPECT_EQ(cloud.box.col0, expected.col0) << "trial " << trial;
    EXPECT_EQ(cloud.box.row0, expected.row0) << "trial " << trial;
    EXPECT_EQ(cloud.box.col1, expected.col1) << "trial " << trial;
    EXPECT_EQ(cloud.box.row1, expected.row1) << "trial " << trial;
  }
}

TEST(FitPixelRect, NonzeroBoxEqualsTheScanOfEveryPixel) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 200; ++trial) {
    const int width = 1 + static_cast<int>(rng() % 40), height = 1 + static_cast<int>(rng() % 12);
    std::vector<uint8_t> mask(static_cast<size_t>(width) * height, 0);
    const int set = static_cast<int>(rng() % 4);  // 0 to 3 pixels (often none or one)
    for (int k = 0; k < set; ++k) mask[rng() % mask.size()] = static_cast<uint8_t>(1 + rng() % 255);
    PixelRect expected{width, height, -1, -1};
    for (int row = 0; row < height; ++row)
      for (int col = 0; col < width; ++col)
        if (mask[static_cast<size_t>(row) * width + col]) {
          expected = {std::min(expected.col0, col), std::min(expected.row0, row), std::max(expected.col1, col),
                      std::max(expected.row1, row)};
        }
    const PixelRect box = occupied_box(mask, width, height);
    ASSERT_EQ(box.col0, expected.col0) << "trial " << trial;
    ASSERT_EQ(box.col1, expected.col1) << "trial " << trial;
    ASSERT_EQ(box.row0, expected.row0) << "trial " << trial;
    ASSERT_EQ(box.row1, expected.row1) << "trial " << trial;
  }
}

TEST(FitPointCloud, BadInputNamesTheField) {
  const raycast::DepthCamera camera{testing::small_intrinsics(32, 24)};
  const DepthFrame good = testing::render_plane(camera, {0, 0, 2}, {0, 0, -1});
  DepthFrame frame = good;
  frame.width = 31;
  EXPECT_EQ(testing::error_field([&] { build_point_cloud(frame, camera); }), "frame.width");
  frame = good;
  frame.depth_mm.pop_back();
  EXPECT_EQ(testing::error_field([&] { build_point_cloud(frame, camera); }), "frame.depth_mm");
  frame = good;
  frame.body_index.resize(10);
  EXPECT_EQ(testing::error_field([&] { build_point_cloud(frame, camera); }), "frame.body_index");
  frame = good;
  std::fill(frame.body_index.begin(), frame.body_index.end(), kNoBody);
  EXPECT_EQ(testing::error_field([&] { build_point_cloud(frame, camera); }), "frame.body_index");

  raycast::DepthIntrinsics nan_intrinsics = testing::small_intrinsics(32, 24);
  nan_intrinsics.fx = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(testing::error_field([&] { raycast::DepthCamera{nan_intrinsics}; }), "intrinsics.fx");
  nan_intrinsics = testing::small_intrinsics(32, 24);
  nan_intrinsics.cy = std::numeric_limits<double>::infinity();
  EXPECT_EQ(testing::error_field([&] { raycast::DepthCamera{nan_intrinsics}; }), "intrinsics.cy");
}

}  // namespace
}  // namespace posefuse::fit
