#pragma once
// A read-only view of a row-major image that the caller owns (e.g. a decoded cv::Mat's data),
// so that core stages take camera images without depending on OpenCV.
#include <cstdint>

namespace posefuse::geometry {

template <class Pixel>
struct ImageView {
  int width = 0;
  int height = 0;
  const Pixel* pixels = nullptr;  // width * height values, row by row from the top-left
  const Pixel& at(int col, int row) const { return pixels[static_cast<long>(row) * static_cast<long>(width) + col]; }
};

// A rectangle of pixels, bounds inclusive (empty when col0 > col1 or row0 > row1).
struct PixelRect {
  int col0 = 0, row0 = 0, col1 = -1, row1 = -1;
  bool empty() const { return col0 > col1 || row0 > row1; }
};

using GrayImageView = ImageView<std::uint8_t>;    // grey levels
using DepthImageView = ImageView<std::uint16_t>;  // millimetres along the camera's z, 0 = no reading
using IrImageView = ImageView<std::uint16_t>;     // infrared intensities

}  // namespace posefuse::geometry
