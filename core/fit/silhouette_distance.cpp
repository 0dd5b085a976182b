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
  int32_t index = -1;
  if (col >= region.col0 && col <= region.col1 && row >= region.row0 && row <= region.row1) {
    index = closest_pixel[static_cast<size_t>(row) * width + col];
  } else {
    float best = std::numeric_limits<float>::infinity();
    for (int32_t candidate : border_pixels) {
      const float d = quasi_euclidean_distance(candidate % width - col, candidate / width - row);
      if (d < best) {
        best = d;
        index = candidate;
      }
    }
  }
  return {static_cast<double>(index % width), static_cast<double>(index / width)};
}

std::vector<uint8_t> silhouette_of(const DepthFrame& frame) {
  std::vector<uint8_t> silhouette;
  silhouette_of(frame, silhouette);
  return silhouette;
}

void silhouette_of(const DepthFrame& frame, std::vector<uint8_t>& silhouette) {
  silhouette.resize(frame.body_index.size());
  // Plain pointers: through the vectors, each uint8_t store might alias the other vector's
  // members (a char type), which keeps the compiler from vectorising the loop.
  const uint8_t* body_index = frame.body_index.data();
  uint8_t* out = silhouette.data();
  const size_t n = silhouette.size();
  for (size_t i = 0; i < n; ++i) out[i] = body_index[i] != kNoBody;
}

namespace {

// Two-pass chamfer (Rosenfeld-Pfaltz) carrying the closest seed along, over the pixels of
// `region` only: the 8-neighbour path metric with steps 1 and sqrt(2) is exactly the
// quasi-Euclidean distance, and the seed handed along a shortest path is one that attains it.
// Shortest 8-neighbour paths between two pixels of a rectangle stay inside it, so every distance
// in the region is exact with respect to the seeds inside the region.
void chamfer(SilhouetteDistanceMap& map, const PixelRect& region) {
  const int width = map.width;
  float* distance = map.distance_px.data();
  int32_t* closest = map.closest_pixel.data();
  // Pixel `to` takes from pixel `from` when that is shorter; (d, c) hold `to`'s distance and
  // closest pixel while its neighbours are visited (from != to).
  const auto relax = [&](float& d, int32_t& c, size_t from, float step) {
    const float candidate = distance[from] + step;
    if (candidate < d) {
      d = candidate;
      c = closest[from];
    }
  };
  // Rows above the first seed stay infinite in the forward pass: skip them.
  int first_row = region.row1 + 1;
  for (int row = region.row0; row <= region.row1 && first_row > region.row1; ++row)
    for (int col = region.col0; col <= region.col1; ++col)
      if (distance[static_cast<size_t>(row) * width + col] == 0) {
        first_row = row;
        break;
      }
  // Each pixel's neighbours in a fixed order (ties keep the first seed found); the region's first
  // and last columns apart, so that the inner loop runs without the edge tests.
  // A silhouette pixel (distance 0) keeps itself: its neighbours' candidates are all longer.
  const auto forward = [&](size_t i, bool up, bool left, bool right) {
    float d = distance[i];
    if (d == 0) return;
    int32_t c = closest[i];
    if (left) relax(d, c, i - 1, 1.0f);
    if (up) {
      if (left) relax(d, c, i - width - 1, kDiagonalStep);
      relax(d, c, i - width, 1.0f);
      if (right) relax(d, c, i - width + 1, kDiagonalStep);
    }
    distance[i] = d;
    closest[i] = c;
  };
  const auto backward = [&](size_t i, bool down, bool left, bool right) {
    float d = distance[i];
    if (d == 0) return;
    int32_t c = closest[i];
    if (right) relax(d, c, i + 1, 1.0f);
    if (down) {
      if (right) relax(d, c, i + width + 1, kDiagonalStep);
      relax(d, c, i + width, 1.0f);
      if (left) relax(d, c, i + width - 1, kDiagonalStep);
    }
    distance[i] = d;
    closest[i] = c;
  };
  const bool wide = region.col1 > region.col0;
  for (int row = first_row; row <= region.row1; ++row) {
    const bool up = row > region.row0;
    const size_t begin = static_cast<size_t>(row) * width + region.col0,
                 last = static_cast<size_t>(row) * width + region.col1;
    forward(begin, up, false, wide);
    if (up) {
      for (size_t i = begin + 1; i < last; ++i) forward(i, true, true, true);
    } else {
      for (size_t i = begin + 1; i < last; ++i) forward(i, false, true, true);
    }
    if (wide) forward(last, up, true, false);
  }
  for (int row = region.row1; row >= region.row0; --row) {
    const bool down = row < region.row1;
    const size_t begin = static_cast<size_t>(row) * width + region.col0,
                 last = static_cast<size_t>(row) * width + region.col1;
    backward(last, down, wide, false);
    if (!wide) continue;  // one column: last == begin (and i = last - 1 could wrap at pixel 0)
    if (down) {
      for (size_t i = last - 1; i > begin; --i) backward(i, true, true, true);
    } else {
      for (size_t i = last - 1; i > begin; --i) backward(i, false, true, true);
    }
    backward(begin, down, false, true);
  }
}

}  // namespace

SilhouetteDistanceMap silhouette_distance_map(const std::vector<uint8_t>& silhouette, int width, int height) {
  return silhouette_distance_map(silhouette, width, height, PixelRect{0, 0, width - 1, height - 1});
}

namespace {

// silhouette_distance_map over `region` into `map`; with_border: also the border pixels
// (closest() outside the region). The map's arrays are reused when they have the image's size:
// only their previous region holds anything to clear.
void distance_map_in(const std::vector<uint8_t>& silhouette, int width, int height, const PixelRect& region,
                     bool with_border, SilhouetteDistanceMap& map) {
  if (width <= 0 || height <= 0)
    throw_invalid("silhouette", "size " + std::to_string(width) + "x" + std::to_string(height) + " is not valid");
  const size_t pixels = static_cast<size_t>(width) * height;
  if (silhouette.size() != pixels)
    throw_invalid("silhouette",
                  "has " + std::to_string(silhouette.size()) + " values, expected " + std::to_string(pixels));
  if (region.col0 < 0 || region.row0 < 0 || region.col1 >= width || region.row1 >= height ||
      region.col0 > region.col1 || region.row0 > region.row1)
    throw_invalid("region", "[" + std::to_string(region.col0) + ", " + std::to_string(region.col1) + "] x [" +
                                std::to_string(region.row0) + ", " + std::to_string(region.row1) +
                                "] is empty or leaves the image");
  if (map.width == width && map.height == height && map.distance_px.size() == pixels &&
      map.closest_pixel.size() == pixels) {
    const PixelRect& previous = map.region;
    for (int row = previous.row0; row <= previous.row1; ++row) {
      const size_t begin = static_cast<size_t>(row) * width + previous.col0;
      const size_t length = static_cast<size_t>(previous.col1 - previous.col0 + 1);
      std::fill_n(map.distance_px.begin() + static_cast<ptrdiff_t>(begin), length,
                  std::numeric_limits<float>::infinity());
      std::fill_n(map.closest_pixel.begin() + static_cast<ptrdiff_t>(begin), length, -1);
    }
  } else {
    map.width = width;
    map.height = height;
    map.distance_px.assign(pixels, std::numeric_limits<float>::infinity());
    map.closest_pixel.assign(pixels, -1);
  }
  map.region = region;
  map.border_pixels.clear();
  bool any = false;
  for (int row = region.row0; row <= region.row1; ++row)
    for (int col = region.col0; col <= region.col1; ++col) {
      const size_t i = static_cast<size_t>(row) * width + col;
      if (!silhouette[i]) continue;
      map.distance_px[i] = 0;
      map.closest_pixel[i] = static_cast<int32_t>(i);
      any = true;
      if (!with_border) continue;
      bool border = row == region.row0 || row == region.row1 || col == region.col0 || col == region.col1;
      for (int dr = -1; dr <= 1 && !border; ++dr)
        for (int dc = -1; dc <= 1 && !border; ++dc) border = !silhouette[i + static_cast<size_t>(dr * width + dc)];
      if (border) map.border_pixels.push_back(static_cast<int32_t>(i));
    }
  if (!any) throw_precondition("silhouette", "is empty");
  chamfer(map, region);
}

}  // namespace

SilhouetteDistanceMap silhouette_distance_map(const std::vector<uint8_t>& silhouette, int width, int height,
                                              const PixelRect& region) {
  SilhouetteDistanceMap map;
  distance_map_in(silhouette, width, height, region, false, map);
  return map;
}

SilhouetteDistanceMap silhouette_distance_map_near(const std::vector<uint8_t>& silhouette, int width, int height,
                                                   int margin_px) {
  SilhouetteDistanceMap map;
  silhouette_distance_map_near(silhouette, width, height, map, margin_px);
  return map;
}

void silhouette_distance_map_near(const std::vector<uint8_t>& silhouette, int width, int height,
                                  SilhouetteDistanceMap& map, int margin_px) {
  if (width <= 0 || height <= 0 || silhouette.size() != static_cast<size_t>(width) * height)
    throw_invalid("silhouette", "has " + std::to_string(silhouette.size()) + " values for a " + std::to_string(width) +
                                    "x" + std::to_string(height) + " image");
  const PixelRect box = occupied_box(silhouette, width, height);
  if (box.col1 < 0) throw_precondition("silhouette", "is empty");
  const int margin = std::max(0, margin_px);
  distance_map_in(silhouette, width, height,
                  PixelRect{std::max(0, box.col0 - margin), std::max(0, box.row0 - margin),
                            std::min(width - 1, box.col1 + margin), std::min(height - 1, box.row1 + margin)},
                  true, map);
}

}  // namespace posefuse::fit
