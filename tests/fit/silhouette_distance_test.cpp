#include "fit/silhouette_distance.hpp"

#include <gtest/gtest.h>

#include <algorithm>
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

// Restricted to a region that holds every silhouette pixel, the map equals the full-image map
// inside the region (distances exactly; the closest pixel attains the same distance) and is
// empty outside it.
TEST(FitSilhouetteDistance, RegionMapEqualsTheFullMapInsideTheRegion) {
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const int width = 40 + trial, height = 30 + trial / 2;
    std::vector<uint8_t> silhouette(static_cast<size_t>(width) * height, 0);
    std::uniform_int_distribution<int> col(8, width - 9), row(6, height - 7), size(1, 6);
    PixelRect box{width, height, -1, -1};
    for (int blob = 0; blob < 1 + trial % 4; ++blob) {
      const int c = col(rng), r = row(rng), half = size(rng);
      for (int y = r - half / 2; y <= r + half; ++y)
        for (int x = c - half; x <= c + half / 2; ++x) {
          silhouette[static_cast<size_t>(y) * width + x] = 1;
          box = {std::min(box.col0, x), std::min(box.row0, y), std::max(box.col1, x), std::max(box.row1, y)};
        }
    }
    const int grow = trial % 5;
    const PixelRect region{std::max(0, box.col0 - grow), std::max(0, box.row0 - grow),
                           std::min(width - 1, box.col1 + grow), std::min(height - 1, box.row1 + grow)};
    const SilhouetteDistanceMap full = silhouette_distance_map(silhouette, width, height);
    const SilhouetteDistanceMap part = silhouette_distance_map(silhouette, width, height, region);
    for (int r = 0; r < height; ++r)
      for (int c = 0; c < width; ++c) {
        const size_t i = static_cast<size_t>(r) * width + c;
        const bool inside = c >= region.col0 && c <= region.col1 && r >= region.row0 && r <= region.row1;
        if (!inside) {
          EXPECT_EQ(part.closest_pixel[i], -1);
          EXPECT_EQ(part.distance_px[i], std::numeric_limits<float>::infinity());
          continue;
        }
        ASSERT_EQ(part.distance_px[i], full.distance_px[i]) << "trial " << trial << " pixel " << c << ", " << r;
        const int32_t k = part.closest_pixel[i];
        ASSERT_TRUE(silhouette[static_cast<size_t>(k)]);
        EXPECT_NEAR(quasi_euclidean_distance(k % width - c, k / width - r), full.distance_px[i], 1e-4);
      }
  }
  const std::vector<uint8_t> one(12, 1);
  EXPECT_EQ(testing::error_field([&] { silhouette_distance_map(one, 4, 3, PixelRect{0, 0, 4, 2}); }), "region");
  EXPECT_EQ(testing::error_field([&] { silhouette_distance_map(one, 4, 3, PixelRect{2, 0, 1, 2}); }), "region");
}

// The two-pass chamfer written plainly (every pixel tests the region's edges): the map must match
// it exactly, closest pixels included (the same neighbour order breaks ties the same way).
void plain_chamfer(const std::vector<uint8_t>& silhouette, int width, const PixelRect& region,
                   std::vector<float>& distance, std::vector<int32_t>& closest) {
  const auto relax = [&](size_t to, size_t from, float step) {
    if (distance[from] + step < distance[to]) {
      distance[to] = distance[from] + step;
      closest[to] = closest[from];
    }
  };
  const float diagonal = 1.41421356f;
  for (int row = region.row0; row <= region.row1; ++row)
    for (int col = region.col0; col <= region.col1; ++col) {
      const size_t i = static_cast<size_t>(row) * width + col;
      if (silhouette[i]) {
        distance[i] = 0;
        closest[i] = static_cast<int32_t>(i);
      }
    }
  for (int row = region.row0; row <= region.row1; ++row)
    for (int col = region.col0; col <= region.col1; ++col) {
      const size_t i = static_cast<size_t>(row) * width + col;
      const bool up = row > region.row0, left = col > region.col0, right = col < region.col1;
      if (left) relax(i, i - 1, 1.0f);
      if (up && left) relax(i, i - width - 1, diagonal);
      if (up) relax(i, i - width, 1.0f);
      if (up && right) relax(i, i - width + 1, diagonal);
    }
  for (int row = region.row1; row >= region.row0; --row)
    for (int col = region.col1; col >= region.col0; --col) {
      const size_t i = static_cast<size_t>(row) * width + col;
      const bool down = row<region.row1, left = col> region.col0, right = col < region.col1;
      if (right) relax(i, i + 1, 1.0f);
      if (down && right) relax(i, i + width + 1, diagonal);
      if (down) relax(i, i + width, 1.0f);
      if (down && left) relax(i, i + width - 1, diagonal);
    }
}

TEST(FitSilhouetteDistance, ChamferEqualsThePlainTwoPassChamferExactly) {
  const int width = 31, height = 19;
  const std::vector<PixelRect> regions = {{0, 0, width - 1, height - 1},
                                          {0, 0, 0, 0},
                                          {0, 0, 0, height - 1},
                                          {0, 0, width - 1, 0},
                                          {5, 3, 5, 12},
                                          {4, 2, 20, 2},
                                          {3, 4, 17, 15},
                                          {29, 17, 30, 18}};
  for (int trial = 0; trial < 6; ++trial)
    for (const PixelRect& region : regions) {
      std::vector<uint8_t> silhouette =
          random_silhouette(width, height, 0.03 + 0.1 * trial, 40 + static_cast<uint64_t>(trial));
      silhouette[static_cast<size_t>(region.row0) * width + region.col0] = 1;  // at least one seed inside
      const SilhouetteDistanceMap map = silhouette_distance_map(silhouette, width, height, region);
      std::vector<float> distance(static_cast<size_t>(width) * height, std::numeric_limits<float>::infinity());
      std::vector<int32_t> closest(distance.size(), -1);
      plain_chamfer(silhouette, width, region, distance, closest);
      ASSERT_EQ(map.distance_px, distance) << "trial " << trial << " region " << region.col0 << ".." << region.col1;
      ASSERT_EQ(map.closest_pixel, closest) << "trial " << trial << " region " << region.col0 << ".." << region.col1;
    }
}

TEST(FitSilhouetteDistance, SilhouetteOfMarksEveryBodyIndexButNoBody) {
  // Odd length (the vectorised loop's tail) and every body-index value, kNoBody among them.
  DepthFrame frame;
  frame.width = 37;
  frame.height = 9;
  frame.body_index.resize(37 * 9);
  std::mt19937 rng(7);
  for (auto& b : frame.body_index) b = rng() % 3 == 0 ? kNoBody : static_cast<uint8_t>(rng() % 256);
  const std::vector<uint8_t> silhouette = silhouette_of(frame);
  ASSERT_EQ(silhouette.size(), frame.body_index.size());
  for (size_t i = 0; i < silhouette.size(); ++i)
    EXPECT_EQ(silhouette[i], frame.body_index[i] != kNoBody ? 1 : 0) << "pixel " << i;
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

// The fitter's map (chamfer near the silhouette's box, border search beyond it): every pixel of
// the image and points far outside it get a closest silhouette pixel as close as the full map's.
TEST(FitSilhouetteDistance, NearMapFindsPixelsAsCloseAsTheFullMapEverywhere) {
  const int width = 60, height = 45;
  std::mt19937_64 rng(8);
  for (int trial = 0; trial < 10; ++trial) {
    // A blob of random pixels in a random sub-rectangle (so that much of the image lies outside).
    std::vector<uint8_t> silhouette(static_cast<size_t>(width) * height, 0);
    const int c0 = static_cast<int>(rng() % 30), r0 = static_cast<int>(rng() % 20);
    const int c1 = c0 + 3 + static_cast<int>(rng() % 20), r1 = r0 + 3 + static_cast<int>(rng() % 15);
    for (int r = r0; r <= r1; ++r)
      for (int c = c0; c <= c1; ++c) silhouette[static_cast<size_t>(r) * width + c] = rng() % 3 != 0;
    silhouette[static_cast<size_t>(r0) * width + c0] = 1;
    const SilhouetteDistanceMap full = silhouette_distance_map(silhouette, width, height);
    const int margin = static_cast<int>(trial % 3) * 2;  // 0, 2, 4
    const SilhouetteDistanceMap near = silhouette_distance_map_near(silhouette, width, height, margin);
    EXPECT_LT((near.region.col1 - near.region.col0 + 1) * (near.region.row1 - near.region.row0 + 1), width * height);
    for (int row = -20; row < height + 20; row += 1)
      for (int col = -20; col < width + 20; col += 1) {
        const Eigen::Vector2d expected = full.closest(col, row), got = near.closest(col, row);
        ASSERT_TRUE(silhouette[static_cast<size_t>(got.y()) * width + static_cast<size_t>(got.x())]);
        // Distances from the clamped query pixel, as closest() looks up.
        const int qc = std::clamp(col, 0, width - 1), qr = std::clamp(row, 0, height - 1);
        const auto distance = [&](const Eigen::Vector2d& p) {
          return quasi_euclidean_distance(static_cast<int>(p.x()) - qc, static_cast<int>(p.y()) - qr);
        };
        ASSERT_NEAR(distance(got), distance(expected), 1e-4) << "trial " << trial << " at " << col << ", " << row;
        const size_t i = static_cast<size_t>(qr) * width + qc;
        ASSERT_EQ(near.distance_px[i] == 0, full.distance_px[i] == 0);  // the fitter's inside test
      }
  }
  EXPECT_EQ(testing::error_field([] { silhouette_distance_map_near(std::vector<uint8_t>(12, 0), 4, 3); }),
            "silhouette");
  EXPECT_EQ(testing::error_field([] { silhouette_distance_map_near(std::vector<uint8_t>(11, 1), 4, 3); }),
            "silhouette");
}

TEST(FitSilhouetteDistance, BadInputNamesTheField) {
  EXPECT_EQ(testing::error_field([] { silhouette_distance_map(std::vector<uint8_t>(10, 1), 4, 3); }), "silhouette");
  EXPECT_EQ(testing::error_field([] { silhouette_distance_map(std::vector<uint8_t>(12, 0), 4, 3); }), "silhouette");
  EXPECT_EQ(testing::error_field([] { silhouette_distance_map({}, 0, 3); }), "silhouette");
}

}  // namespace
}  // namespace posefuse::fit
