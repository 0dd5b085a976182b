#include "fit/depth_frame.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>

#include "common/error.hpp"

namespace posefuse::fit {

PixelRect occupied_box(const std::vector<uint8_t>& mask, int width, int height, uint8_t empty) {
  PixelRect box{width, height, -1, -1};
  // Per row: skip empty 8-byte words from each end (most of a frame is background).
  const uint64_t empty_word = 0x0101010101010101ull * empty;
  const auto is_empty_word = [empty_word](const uint8_t* p) {
    uint64_t word;
    std::memcpy(&word, p, sizeof word);
    return word == empty_word;
  };
  for (int row = 0; row < height; ++row) {
    const uint8_t* line = mask.data() + static_cast<size_t>(row) * width;
    int first = 0;
    while (first + 8 <= width && is_empty_word(line + first)) first += 8;
    while (first < width && line[first] == empty) ++first;
    if (first == width) continue;
    int last = width - 1;
    while (last - 7 > first && is_empty_word(line + last - 7)) last -= 8;
    while (line[last] == empty) --last;
    box.col0 = std::min(box.col0, first);
    box.col1 = std::max(box.col1, last);
    box.row0 = std::min(box.row0, row);
    box.row1 = row;
  }
  return box;
}

void validate(const DepthFrame& frame, const raycast::DepthCamera& camera) {
  if (frame.width != camera.width() || frame.height != camera.height())
    throw_invalid("frame.width", std::to_string(frame.width) + "x" + std::to_string(frame.height) +
                                     " does not match the camera's " + std::to_string(camera.width()) + "x" +
                                     std::to_string(camera.height()));
  const size_t pixels = static_cast<size_t>(frame.width) * frame.height;
  if (frame.depth_mm.size() != pixels)
    throw_invalid("frame.depth_mm",
                  "has " + std::to_string(frame.depth_mm.size()) + " values, expected " + std::to_string(pixels));
  if (frame.body_index.size() != pixels)
    throw_invalid("frame.body_index",
                  "has " + std::to_string(frame.body_index.size()) + " values, expected " + std::to_string(pixels));
}

VectorImage VectorImage::empty(int width, int height) {
  VectorImage image;
  image.width = width;
  image.height = height;
  const size_t pixels = static_cast<size_t>(width) * height;
  image.value_K.assign(pixels, Eigen::Vector3f::Zero());
  image.valid.assign(pixels, 0);
  return image;
}

PointCloud build_point_cloud(const DepthFrame& frame, const raycast::DepthCamera& camera) {
  PointCloud cloud;
  build_point_cloud(frame, camera, cloud);
  return cloud;
}

void build_point_cloud(const DepthFrame& frame, const raycast::DepthCamera& camera, PointCloud& cloud) {
  validate(frame, camera);
  const size_t pixels = static_cast<size_t>(frame.width) * frame.height;
  if (cloud.width == frame.width && cloud.height == frame.height && cloud.value_K.size() == pixels &&
      cloud.valid.size() == pixels) {
    // Every valid pixel lies in the box: clearing it leaves an empty image.
    const PixelRect& box = cloud.box;
    for (int row = box.row0; row <= box.row1; ++row) {
      const size_t begin = static_cast<size_t>(row) * frame.width + box.col0;
      const size_t length = static_cast<size_t>(box.col1 - box.col0 + 1);
      std::fill_n(cloud.value_K.begin() + static_cast<ptrdiff_t>(begin), length, Eigen::Vector3f::Zero());
      std::fill_n(cloud.valid.begin() + static_cast<ptrdiff_t>(begin), length, uint8_t{0});
    }
    cloud.count = 0;
    cloud.box = PixelRect{};
  } else {
    cloud = VectorImage::empty(frame.width, frame.height);
  }
  // Pixels are written directly (not through set()) so that the box is updated once per row.
  Eigen::Vector3f* value = cloud.value_K.data();
  uint8_t* valid = cloud.valid.data();
  for (int row = 0; row < frame.height; ++row) {
    const uint8_t* body = frame.body_index.data() + static_cast<size_t>(row) * frame.width;
    const uint16_t* depth = frame.depth_mm.data() + static_cast<size_t>(row) * frame.width;
    const size_t row_start = static_cast<size_t>(row) * frame.width;
    int first = frame.width, last = -1;
    for (int col = 0; col < frame.width;) {
      if (col + 8 <= frame.width && background_word(body + col)) {
        col += 8;
        continue;
      }
      for (const int end = std::min(frame.width, col + 8); col < end; ++col) {
        if (body[col] == kNoBody || depth[col] == kNoDepth) continue;
        // Depth images store z, and pixel_ray has z = 1, so the point is z times the ray.
        value[row_start + col] = camera.pixel_ray(col, row) * (depth[col] * 1e-3f);
        valid[row_start + col] = 1;
        ++cloud.count;
        first = std::min(first, col);
        last = col;
      }
    }
    if (last < 0) continue;
    if (cloud.box.col1 < 0) cloud.box = {first, row, last, row};
    cloud.box = {std::min(cloud.box.col0, first), cloud.box.row0, std::max(cloud.box.col1, last), row};
  }
  if (cloud.count == 0) throw_precondition("frame.body_index", "the silhouette holds no pixel with a depth reading");
}

}  // namespace posefuse::fit
