#include "fit/packed_body_frame.hpp"

#include <algorithm>
#include <limits>
#include <string>

#include "common/error.hpp"

namespace posefuse::fit {

std::size_t PackedBodyFrame::bytes() const {
  return run_start.capacity() * sizeof(std::uint32_t) + run_length.capacity() * sizeof(std::uint16_t) +
         run_body_index.capacity() + depth_mm.capacity() * sizeof(std::uint16_t);
}

PackedBodyFrame pack_body_pixels(const DepthFrame& frame) {
  if (frame.width <= 0 || frame.height <= 0)
    throw_invalid("frame.width",
                  std::to_string(frame.width) + "x" + std::to_string(frame.height) + " is not an image size");
  const std::size_t pixels = static_cast<std::size_t>(frame.width) * static_cast<std::size_t>(frame.height);
  if (pixels > std::numeric_limits<std::uint32_t>::max())
    throw_invalid("frame.width", std::to_string(frame.width) + "x" + std::to_string(frame.height) + " is too large");
  if (frame.depth_mm.size() != pixels)
    throw_invalid("frame.depth_mm",
                  "has " + std::to_string(frame.depth_mm.size()) + " values, expected " + std::to_string(pixels));
  if (frame.body_index.size() != pixels)
    throw_invalid("frame.body_index",
                  "has " + std::to_string(frame.body_index.size()) + " values, expected " + std::to_string(pixels));
  PackedBodyFrame packed;
  packed.width = frame.width;
  packed.height = frame.height;
  const auto width = static_cast<std::size_t>(frame.width);
  for (std::size_t row_start = 0; row_start < pixels; row_start += width) {
    // Runs end at row ends too, so that unpacking needs no wrap-around.
    for (std::size_t i = row_start; i < row_start + width;) {
      if (i + 8 <= row_start + width && background_word(frame.body_index.data() + i)) {
        i += 8;
        continue;
      }
      const std::uint8_t body = frame.body_index[i];
      if (body == kNoBody) {
        ++i;
        continue;
      }
      std::size_t end = i;
      while (end < row_start + width && frame.body_index[end] == body &&
             end - i < std::numeric_limits<std::uint16_t>::max())
        ++end;
      packed.run_start.push_back(static_cast<std::uint32_t>(i));
      packed.run_length.push_back(static_cast<std::uint16_t>(end - i));
      packed.run_body_index.push_back(body);
      packed.depth_mm.insert(packed.depth_mm.end(), frame.depth_mm.begin() + static_cast<std::ptrdiff_t>(i),
                             frame.depth_mm.begin() + static_cast<std::ptrdiff_t>(end));
      i = end;
    }
  }
  packed.run_start.shrink_to_fit();
  packed.run_length.shrink_to_fit();
  packed.run_body_index.shrink_to_fit();
  packed.depth_mm.shrink_to_fit();
  return packed;
}

DepthFrame unpack_body_pixels(const PackedBodyFrame& packed) {
  DepthFrame frame;
  frame.width = packed.width;
  frame.height = packed.height;
  const std::size_t pixels = static_cast<std::size_t>(packed.width) * static_cast<std::size_t>(packed.height);
  frame.depth_mm.assign(pixels, kNoDepth);
  frame.body_index.assign(pixels, kNoBody);
  std::size_t next_depth = 0;
  for (std::size_t r = 0; r < packed.run_start.size(); ++r) {
    const std::size_t start = packed.run_start[r], length = packed.run_length[r];
    std::fill_n(frame.body_index.begin() + static_cast<std::ptrdiff_t>(start), length, packed.run_body_index[r]);
    std::copy_n(packed.depth_mm.begin() + static_cast<std::ptrdiff_t>(next_depth), length,
                frame.depth_mm.begin() + static_cast<std::ptrdiff_t>(start));
    next_depth += length;
  }
  return frame;
}

}  // namespace posefuse::fit
