#include "fit/silhouette_distance.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "synthetic_frames.hpp"

namespace posefuse::fit {
namespace {

std::vector<uint8_t> random_silhouette(int width, int height, double fill, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::bernoulli_distribution on(fill);
  std::vector<uint8_t> s(static_cast<size_t>(width) * height);
  for (auto& v : s) v = on(rng);
  return s;
}

void expect_equals_brute_force(const std::vector<uint8_t>& silhouette, int width, int height) {
  const SilhouetteDistanceMap map = silhouette_distance_map(silhouette, width, height);
  for (int row = 0; row < height; ++row)
    for (int col = 0; col < width; ++col) {
      float best = std::numeric_limits<float>::infinity();
      for (int r = 0; r < height; ++r)
        for (int c = 0; c < width; ++c)
          if (silhouette[r * width + c]) best = std::min(best, quasi_euclidean_distance(c - col, r - row));
      const size_t i = static_cast<size_t>(row) * width + col;
      ASSERT_NEAR(map.distance_px[i], best, 1e-4) << "pixel " << col << ", " << row;
      const int32_t closest = map.closest_pixel[i];
      ASSERT_TRUE(silhouette[closest]);
      EXPECT_NEAR(quasi_euclidean_distance(closest % width - col, closest / width - row), best, 1e-4);
      const Eigen::Vector2d d2d = map.closest(col, row);
      EXPECT_EQ(d2d, Eigen::Vector2d(closest % width, closest / width));
    }
}

TEST(FitSilhouetteDistance, EqualsBruteForceOnRandomSilhouettes) {
  expect_equals_brute_force(random_silhouette(37, 23, 0.05, 1), 37, 23);
  expect_equals_brute_force(random_silhouette(20, 31, 0.01, 2), 20, 31);
  expect_equals_brute_force(random_silhouette(25, 25, 0.5, 3), 25, 25);
}

TEST(FitSilhouetteDistance, EqualsBruteForceOnASinglePixelAndADisk) {
  std::vector<uint8_t> one(30 * 20, 0);
  one[19 * 30 + 29] = 1;  // bottom-right corner: distances grow across the whole image
  expect_equals_brute_force(one, 30, 20);
  std::vector<uint8_t> disk(40 * 30, 0);
  for (int r = 0; r < 30; ++r)
    for (int c = 0; c < 40; ++c) disk[r * 40 + c] = (c - 12) * (c - 12) + (r - 17) * (r - 17) <= 36;
  expect_equals_brute_force(disk, 40, 30);
}

TEST(FitSilhouetteDistance, InsideIsIdentityAndOutsideImageIsClamped) {
  const raycast::DepthCamera camera{testing::small_intrinsics(64, 53)};
  const DepthFrame frame = testing::render_sphere(camera, {0, 0, 1}, 0.2);
  const SilhouetteDistanceMap map = silhouette_distance_map(silhouette_of(frame), 64, 53);
  EXPECT_EQ(map.closest(32, 26), Eigen::Vector2d(32, 26));
  EXPECT_EQ(map.closest(-100, 26), map.closest(0, 26));
  EXPECT_EQ(map.closest(32, 1e9), map.closest(32, 52));
  EXPECT_EQ(map.closest(std::nan(""), 26), map.closest(0, 26));
}

TEST(FitSilhouetteDistance, BadInputNamesTheField) {
  EXPECT_EQ(testing::error_field([] { silhouette_distance_map(std::vector<uint8_t>(10, 1), 4, 3); }), "silhouette");
  EXPECT_EQ(testing::error_field([] { silhouette_distance_map(std::vector<uint8_t>(12, 0), 4, 3); }), "silhouette");
  EXPECT_EQ(testing::error_field([] { silhouette_distance_map({}, 0, 3); }), "silhouette");
}

}  // namespace
}  // namespace posefuse::fit
