#pragma once
// A colour frame as the stages get it. Only the forearm stage's strap search looks at colour, and
// only along each forearm (a few thousand of the frame's pixels), so a JPEG frame is kept encoded
// and decoded to grey over the rows and columns asked for: libjpeg-turbo skips the IDCT and the
// colour conversion of every other block, and one pass decodes every rectangle a frame needs (both
// forearms) without reading the rows below the lowest (on the demo's 960 x 540 frames 0.28 ms
// against 0.88 ms for the whole frame; docs/benchmarks.md, "Depth, body index and colour decoding
// per frame"). The pixels decoded are the whole frame's decode's, exactly. A PNG frame (no such
// shortcut) is decoded to grey when it arrives.
#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include <opencv2/core.hpp>

#include "geometry/image_view.hpp"
#include "posefuse/v1/session.pb.h"

namespace posefuse::session {

class ColorImage {
 public:
  ColorImage() = default;
  // Checks the frame as decode_color_gray does before it decodes (encoding, size against the
  // chunk's, the JPEG's headers up to the start of its pixel data; a PNG is decoded) and throws
  // posefuse::Error (kInvalidArgument) naming `field` + ".data" (or ".encoding").
  static ColorImage from_frame(const v1::ColorFrame& frame, const std::string& field = "color");

  bool empty() const { return width_ == 0; }
  int width() const { return width_; }
  int height() const { return height_; }
  // Bytes this image holds (the encoded JPEG or the decoded grey levels).
  std::size_t held_bytes() const;

  // Writes the grey levels of `rects` (each clipped to the image) into `gray`, a CV_8UC1 image of
  // the frame's size (reallocated and zeroed when it is not): the pixels inside every rectangle are
  // the frame's; rows outside them all keep what `gray` held, and within their rows other columns
  // between the leftmost and the rightmost rectangle may be written (a JPEG is decoded in one pass
  // over the columns they span, in whole blocks). Throws posefuse::Error (kInvalidArgument) naming
  // `field` + ".data" when the JPEG's pixel data cannot be decoded.
  void decode_gray(std::span<const geometry::PixelRect> rects, cv::Mat& gray, const std::string& field = "color") const;
  void decode_gray(const geometry::PixelRect& rect, cv::Mat& gray, const std::string& field = "color") const {
    decode_gray(std::span<const geometry::PixelRect>(&rect, 1), gray, field);
  }

 private:
  int width_ = 0, height_ = 0;
  std::shared_ptr<const std::string> jpeg_;  // JPEG: the encoded frame
  cv::Mat gray_;                             // PNG: the decoded grey levels (CV_8UC1)
};

}  // namespace posefuse::session
