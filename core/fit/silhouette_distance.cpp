#include "fit/silhouette_distance.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "common/error.hpp"

namespace posefuse::fit {

namespace {
constexpr float kDiagonalStep = 1.41421356f;
}

float quasi_euclidean_distance(int dx, int dy) {
  const int a = std::abs(dx), b = std::abs(dy);
  return static_cast<float>(std::max(a, b)) + (kDiagonalStep - 1.0f) * static_cast<float>(std::min(a, b));
}

Eigen::Vector2d SilhouetteDistanceMap::closest(double u, double v) const {
  const int col = std::clamp(static_cast<int>(std::lround(std::isfinite(u) ? u : 0.0)), 0, width - 1);
  const int row = std::clamp(static_cast<int>(std::lround(std::isfinite(v) ? v : 0.0)), 0, height - 1);
  const int32_t index = closest_pixel[static_cast<size_t>(row) * width + col];
  return {static_cast<double>(index % width), static_cast<double>(index / width)};
}

std::vector<uint8_t> silhouette_of(const DepthFrame& frame) {
  std::vector<uint8_t> silhouette(frame.body_index.size());
  for (size_t i = 0; i < silhouette.size(); ++i) silhouette[i] = frame.body_index[i] != kNoBody;
  return silhouette;
}

// Two-pass chamfer (Rosenfeld-Pfaltz) carrying the closest seed along: the 8-neighbour path metric
// with steps 1 and sqrt(2) is exactly the quasi-Euclidean distance, and the seed handed along a
// shortest path is one that attains it.
SilhouetteDistanceMap silhouette_distance_map(const std::vector<uint8_t>& silhouette, int width, int height) {
  if (width <= 0 || height <= 0)
    throw_invalid("silhouette", "size " + std::to_string(width) + "x" + std::to_string(height) + " is not valid");
  const size_t pixels = static_cast<size_t>(width) * height;
  if (silhouette.size() != pixels)
    throw_invalid("silhouette", "has " + std::to_string(silhouette.size()) + " values, expected " + std::to_string(pixels));
  SilhouetteDistanceMap map;
  map.width = width;
  map.height = height;
  map.distance_px.assign(pixels, std::numeric_limits<float>::infinity());
  map.closest_pixel.assign(pixels, -1);
  bool any = false;
  for (size_t i = 0; i < pixels; ++i)
    if (silhouette[i]) {
      map.distance_px[i] = 0;
      map.closest_pixel[i] = static_cast<int32_t>(i);
      any = true;
    }
  if (!any) throw_precondition("silhouette", "is empty");

  auto relax = [&](int col, int row, int dc, int dr, float step) {
    const int nc = col + dc, nr = row + dr;
    if (nc < 0 || nr < 0 || nc >= width || nr >= height) return;
    const size_t from = static_cast<size_t>(nr) * width + nc, to = static_cast<size_t>(row) * width + col;
    const float candidate = map.distance_px[from] + step;
    if (candidate < map.distance_px[to]) {
      map.distance_px[to] = candidate;
      map.closest_pixel[to] = map.closest_pixel[from];
    }
  };
  for (int row = 0; row < height; ++row)
    for (int col = 0; col < width; ++col) {
      relax(col, row, -1, 0, 1.0f);
      relax(col, row, -1, -1, kDiagonalStep);
      relax(col, row, 0, -1, 1.0f);
      relax(col, row, 1, -1, kDiagonalStep);
    }
  for (int row = height - 1; row >= 0; --row)
    for (int col = width - 1; col >= 0; --col) {
      relax(col, row, 1, 0, 1.0f);
      relax(col, row, 1, 1, kDiagonalStep);
      relax(col, row, 0, 1, 1.0f);
      relax(col, row, -1, 1, kDiagonalStep);
    }
  return map;
}

}  // namespace posefuse::fit
