#pragma once
// A depth frame reduced to what the fit reads from it: the silhouette and the depth of its pixels
// (point cloud, normals, D_2D, D_3D and the silhouette cleanup never read depth outside the body
// index). The body-fit stage keeps the frames that wait for their forearm orientations in this
// form: about 2 bytes per body pixel plus 9 bytes per row run (~40 kB for a person at 2.5 m)
// instead of 3 bytes per image pixel (651 kB at 512 x 424), so waiting many seconds for IMU data
// that arrive late in the stream costs tens of megabytes, not hundreds.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fit/depth_frame.hpp"

namespace posefuse::fit {

struct PackedBodyFrame {
  int width = 0;
  int height = 0;
  // Runs of row-adjacent pixels with the same body index (!= kNoBody), in row-major order.
  std::vector<std::uint32_t> run_start;  // pixel index (row * width + col) of the run's first pixel
  std::vector<std::uint16_t> run_length;
  std::vector<std::uint8_t> run_body_index;
  std::vector<std::uint16_t> depth_mm;  // every run pixel's depth, runs concatenated
  std::size_t bytes() const;            // heap bytes held
};

// Throws posefuse::Error ("frame.width", "frame.depth_mm", "frame.body_index") for a frame whose
// buffers do not hold width x height pixels (or a non-positive size).
PackedBodyFrame pack_body_pixels(const DepthFrame& frame);

// The frame back: body pixels as packed, every other pixel kNoBody with kNoDepth.
DepthFrame unpack_body_pixels(const PackedBodyFrame& packed);

}  // namespace posefuse::fit
