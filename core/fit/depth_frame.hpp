#pragma once
// One depth frame as the Kinect v2 SDK gives it, and its point cloud in the camera frame K
// (x left, y up, z forward; metres) through the DepthCamera's unprojection (paper 2, II-A).
#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

#include "geometry/image_view.hpp"
#include "raycast/depth_camera.hpp"

namespace posefuse::fit {

inline constexpr uint16_t kNoDepth = 0;  // depth pixel without a reading
inline constexpr uint8_t kNoBody = 255;  // body-index pixel outside every body

// Whether the 8 body-index pixels from `body` on are all background. Most of a frame is, and the
// per-pixel loops pass over it a word at a time.
inline bool background_word(const uint8_t* body) {
  static_assert(kNoBody == 0xff, "the background word test assumes kNoBody = 0xff");
  uint64_t word;
  std::memcpy(&word, body, sizeof word);
  return word == ~uint64_t{0};
}

using geometry::PixelRect;

// Smallest rectangle holding every pixel other than `empty` of a row-major width x height mask
// (empty when there is none): a 0/1 mask's ones, a body index's body pixels with kNoBody. The
// caller checks mask.size() == width * height.
PixelRect occupied_box(const std::vector<uint8_t>& mask, int width, int height, uint8_t empty = 0);

struct DepthFrame {
  int width = 0;
  int height = 0;
  std::vector<uint16_t> depth_mm;   // row-major, z in millimetres, kNoDepth = no reading
  std::vector<uint8_t> body_index;  // row-major, kNoBody = background
};

// Throws posefuse::Error (field "frame.width", "frame.depth_mm", "frame.body_index") when the
// frame does not match the camera's image size or its buffers have the wrong length.
void validate(const DepthFrame& frame, const raycast::DepthCamera& camera);

// An image of 3D vectors in K (points or normals) where only some pixels hold a value.
struct VectorImage {
  int width = 0;
  int height = 0;
  std::vector<Eigen::Vector3f> value_K;  // zero where !valid
  std::vector<uint8_t> valid;
  int count = 0;  // number of valid pixels
  // Smallest rectangle holding every valid pixel (empty when none): per-pixel passes over the
  // image need to visit only this.
  PixelRect box;

  // width x height pixels, none valid.
  static VectorImage empty(int width, int height);
  // Sets a pixel that is not valid yet.
  void set(int col, int row, const Eigen::Vector3f& v) {
    const size_t pixel = static_cast<size_t>(row) * width + col;
    value_K[pixel] = v;
    valid[pixel] = 1;
    if (count++ == 0) box = {col, row, col, row};
    box = {std::min(box.col0, col), std::min(box.row0, row), std::max(box.col1, col), std::max(box.row1, row)};
  }
  bool has(int col, int row) const { return valid[static_cast<size_t>(row) * width + col] != 0; }
  const Eigen::Vector3f& at(int col, int row) const { return value_K[static_cast<size_t>(row) * width + col]; }
};

// Silhouette pixels with a depth reading (body index != kNoBody and depth > 0), unprojected
// into K, metres.
using PointCloud = VectorImage;

// Throws posefuse::Error (field "frame.body_index") when the silhouette holds no pixel with depth.
PointCloud build_point_cloud(const DepthFrame& frame, const raycast::DepthCamera& camera);
// The same into `cloud`, reusing its buffers when it has the frame's size: only its previous box
// is cleared, so that a frame costs no full-image allocation or clearing.
void build_point_cloud(const DepthFrame& frame, const raycast::DepthCamera& camera, PointCloud& cloud);

}  // namespace posefuse::fit
