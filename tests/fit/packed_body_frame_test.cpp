// PackedBodyFrame: the body-fit stage's waiting frames keep the silhouette and its depth only.
#include "fit/packed_body_frame.hpp"

#include <gtest/gtest.h>

#include <random>

#include "fit/behind_surface_map.hpp"
#include "fit/silhouette_distance.hpp"
#include "synthetic_frames.hpp"

namespace posefuse::fit {
namespace {

// A frame with two people (body ids 0 and 3), runs that touch the image's left and right edges,
// body pixels without depth and background pixels with depth.
DepthFrame two_people(int width, int height, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> noise(-5, 5);
  DepthFrame frame{width, height, std::vector<std::uint16_t>(static_cast<size_t>(width) * height),
                   std::vector<std::uint8_t>(static_cast<size_t>(width) * height, kNoBody)};
  for (int row = 0; row < height; ++row)
    for (int col = 0; col < width; ++col) {
      const size_t i = static_cast<size_t>(row) * width + col;
      frame.depth_mm[i] = static_cast<std::uint16_t>(2000 + 5 * (col + row) + noise(rng));
      const double dx = col - 0.3 * width, dy = row - 0.5 * height;
      if (dx * dx + dy * dy < 0.1 * width * width || col == 0) frame.body_index[i] = 0;
      if ((col > 0.7 * width && row % 3 != 0) || col == width - 1) frame.body_index[i] = 3;
      if (rng() % 50 == 0) frame.depth_mm[i] = kNoDepth;
    }
  return frame;
}

TEST(FitPackedBodyFrame, UnpacksToTheSilhouetteAndItsDepthOnly) {
  // Rows of whole 8-pixel words and rows that end inside one (the background is passed a word at a
  // time).
  for (const auto& [width, height] : {std::pair{64, 48}, std::pair{61, 37}}) {
    const DepthFrame frame = two_people(width, height, 7);
    const PackedBodyFrame packed = pack_body_pixels(frame);
    const DepthFrame back = unpack_body_pixels(packed);
    ASSERT_EQ(back.width, width);
    ASSERT_EQ(back.height, height);
    int body_pixels = 0;
    for (size_t i = 0; i < frame.depth_mm.size(); ++i) {
      EXPECT_EQ(back.body_index[i], frame.body_index[i]) << width << "x" << height << " pixel " << i;
      if (frame.body_index[i] != kNoBody) {
        ++body_pixels;
        EXPECT_EQ(back.depth_mm[i], frame.depth_mm[i]) << "pixel " << i;
      } else {
        EXPECT_EQ(back.depth_mm[i], kNoDepth) << "pixel " << i;  // background depth is not kept
      }
    }
    EXPECT_EQ(packed.depth_mm.size(), static_cast<size_t>(body_pixels));
    EXPECT_LT(packed.bytes(), frame.depth_mm.size() * 3);
  }
}

TEST(FitPackedBodyFrame, AnEmptySilhouetteStaysEmpty) {
  DepthFrame frame = two_people(16, 8, 1);
  frame.body_index.assign(frame.body_index.size(), kNoBody);
  const PackedBodyFrame packed = pack_body_pixels(frame);
  EXPECT_TRUE(packed.run_start.empty());
  const DepthFrame back = unpack_body_pixels(packed);
  for (size_t i = 0; i < back.depth_mm.size(); ++i) {
    EXPECT_EQ(back.body_index[i], kNoBody);
    EXPECT_EQ(back.depth_mm[i], kNoDepth);
  }
}

// What the fit computes from a frame is the same from the unpacked one: the point cloud, D_2D and
// D_3D read only silhouette pixels.
TEST(FitPackedBodyFrame, TheFitsPreprocessingIsUnchanged) {
  const raycast::DepthCamera camera{testing::small_intrinsics(64, 48)};
  const DepthFrame frame = two_people(64, 48, 11);
  const DepthFrame back = unpack_body_pixels(pack_body_pixels(frame));
  const PointCloud a = build_point_cloud(frame, camera), b = build_point_cloud(back, camera);
  ASSERT_EQ(a.count, b.count);
  EXPECT_EQ(a.valid, b.valid);
  EXPECT_EQ(a.value_K, b.value_K);
  const SilhouetteDistanceMap da = silhouette_distance_map(silhouette_of(frame), 64, 48);
  const SilhouetteDistanceMap db = silhouette_distance_map(silhouette_of(back), 64, 48);
  EXPECT_EQ(da.closest_pixel, db.closest_pixel);
  const BehindSurfaceMap ma(frame, camera), mb(back, camera);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> x(-1.0, 1.0), z(1.5, 3.0);
  for (int q = 0; q < 200; ++q) {
    const Eigen::Vector3d p(x(rng), x(rng), z(rng));
    EXPECT_EQ(ma.is_behind(p), mb.is_behind(p));
    EXPECT_EQ(ma.closest_behind(p), mb.closest_behind(p));
  }
}

TEST(FitPackedBodyFrame, BadFramesNameTheField) {
  DepthFrame frame = two_people(16, 8, 2);
  DepthFrame short_depth = frame;
  short_depth.depth_mm.pop_back();
  EXPECT_EQ(testing::error_field([&] { pack_body_pixels(short_depth); }), "frame.depth_mm");
  DepthFrame short_index = frame;
  short_index.body_index.resize(3);
  EXPECT_EQ(testing::error_field([&] { pack_body_pixels(short_index); }), "frame.body_index");
  DepthFrame no_size = frame;
  no_size.width = 0;
  EXPECT_EQ(testing::error_field([&] { pack_body_pixels(no_size); }), "frame.width");
}

}  // namespace
}  // namespace posefuse::fit
