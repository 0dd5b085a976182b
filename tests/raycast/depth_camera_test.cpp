#include "raycast/depth_camera.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "common/error.hpp"

namespace posefuse::raycast {
namespace {

TEST(DepthCamera, DistortionRoundTripOverTheWholeImage) {
  const DepthCamera camera{DepthIntrinsics{}};
  for (double v = -0.5; v <= 423.5; v += 10.5)
    for (double u = -0.5; u <= 511.5; u += 10.5) {
      const Eigen::Vector3d ray = camera.ray_direction(u, v);
      EXPECT_NEAR(ray.norm(), 1.0, 1e-12);
      for (double range : {0.5, 2.0, 7.0}) {
        const auto pixel = camera.project(range * ray);
        ASSERT_TRUE(pixel.has_value());
        EXPECT_NEAR(pixel->x(), u, 1e-7);
        EXPECT_NEAR(pixel->y(), v, 1e-7);
      }
    }
  for (double r = 0; r < 1.2; r += 0.01) EXPECT_NEAR(camera.undistort_radius(camera.distort_radius(r)), r, 1e-12);
}

TEST(DepthCamera, SignConventionsOfFrameK) {
  const DepthCamera camera{DepthIntrinsics{}};
  // K: x left, y up, z forward. Left of the camera -> left half of the image; up -> upper half.
  const auto left = camera.project({0.3, 0, 2});
  const auto up = camera.project({0, 0.3, 2});
  ASSERT_TRUE(left && up);
  EXPECT_LT(left->x(), 256.0);
  EXPECT_NEAR(left->y(), 212.0, 1e-9);
  EXPECT_LT(up->y(), 212.0);
  EXPECT_NEAR(up->x(), 256.0, 1e-9);
  EXPECT_FALSE(camera.project({0, 0, -1}).has_value());
  EXPECT_FALSE(camera.project({5, 0, 1}).has_value());  // 79 deg off axis: outside the model's field
  const Eigen::Vector3f& centre = camera.pixel_ray(256, 212);
  EXPECT_NEAR(centre.x(), 0.f, 1e-7f);
  EXPECT_FLOAT_EQ(centre.z(), 1.f);
  EXPECT_GT(camera.pixel_ray(0, 0).x(), 0.f);  // top-left pixel looks left and up
  EXPECT_GT(camera.pixel_ray(0, 0).y(), 0.f);
}

TEST(DepthCamera, RejectsBadIntrinsics) {
  DepthIntrinsics bad;
  bad.fx = 0;
  EXPECT_THROW(DepthCamera{bad}, Error);
  bad = {};
  bad.width = -3;
  EXPECT_THROW(DepthCamera{bad}, Error);
  bad = {};
  bad.k2 = -3.0;  // folds over inside the image
  EXPECT_THROW(DepthCamera{bad}, Error);
  bad = {};
  bad.cy = std::nan("");
  EXPECT_THROW(DepthCamera{bad}, Error);
}

// columns_within / row_within may only drop pixels whose ray lies outside the box: checked
// against the per-pixel test for boxes all over the (distorted) image.
TEST(DepthCamera, ColumnsAndRowsWithinKeepEveryPixelInsideTheBox) {
  const DepthCamera camera(DepthIntrinsics{});  // Kinect v2 distortion
  int boxes = 0, kept_columns = 0;
  for (float cx = -0.7f; cx <= 0.7f; cx += 0.23f)
    for (float cy = -0.55f; cy <= 0.55f; cy += 0.19f)
      for (const float half : {0.01f, 0.08f, 0.3f}) {
        const float min_x = cx - half, max_x = cx + half, min_y = cy - 0.5f * half, max_y = cy + 0.5f * half;
        const auto [first, last] = camera.columns_within(min_x, max_x);
        ASSERT_LE(0, first);
        ASSERT_LE(first, std::max(first, last));
        ASSERT_LE(last, camera.width());
        for (int row = 0; row < camera.height(); ++row)
          for (int col = 0; col < camera.width(); ++col) {
            const Eigen::Vector3f& d = camera.pixel_ray(col, row);
            if (d.x() < min_x || d.x() > max_x || d.y() < min_y || d.y() > max_y) continue;
            ASSERT_TRUE(col >= first && col < last) << col << " " << row;
            ASSERT_TRUE(camera.row_within(row, min_y, max_y)) << col << " " << row;
          }
        kept_columns += last - first;
        ++boxes;
      }
  // And it does skip: the boxes keep a small part of the columns.
  EXPECT_LT(kept_columns, boxes * camera.width() / 2);
  const auto all = camera.columns_within(-1e30f, 1e30f);
  EXPECT_EQ(all.first, 0);
  EXPECT_EQ(all.second, camera.width());
}

}  // namespace
}  // namespace posefuse::raycast
