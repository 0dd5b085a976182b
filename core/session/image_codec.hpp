#pragma once
// Depth, body index and color frame payloads <-> images.
//
// Decoders check that the payload really is what the chunk says (encoding, width, height, byte
// count) and throw posefuse::Error (kInvalidArgument) naming `field` + ".data" (or ".encoding")
// otherwise, so they double as the validator's size checks.
#include <cstdint>
#include <string>
#include <string_view>

#include <opencv2/core.hpp>

#include "posefuse/v1/session.pb.h"

namespace posefuse::session {

// Largest accepted image side, pixels.
inline constexpr std::uint32_t kMaxImageSide = 8192;
// Largest accepted pixel counts: what a hostile width x height (and a few bytes of zstd or PNG
// that claim to fill it) can make us allocate per decoded frame. Depth-camera images (depth,
// body index) at most 1024 x 1024 pixels, the largest depth mode of Kinect-class cameras
// (2 MiB as u16); colour at most 4096 x 3072, the largest colour mode (12 Mpx).
inline constexpr std::uint64_t kMaxDepthPixels = 1024ull * 1024;
inline constexpr std::uint64_t kMaxColorPixels = 4096ull * 3072;

// Depth frame -> CV_16UC1 (mm, 0 = no reading), from any encoding.
cv::Mat decode_depth(const v1::DepthFrame& frame, const std::string& field = "depth");
// zstd_level: ZSTD_U16_LE only (1 is ~2.5 times faster than 3 on noisy depth, 14 % larger).
v1::DepthFrame encode_depth(const cv::Mat& depth_mm, v1::DepthFrame::Encoding encoding, std::int64_t t_us,
                            int zstd_level = 3);

// Body index frame -> CV_8UC1 (255 = background, else body id 0..5).
cv::Mat decode_body_index(const v1::BodyIndexFrame& frame, const std::string& field = "body_index");
// zstd_level: ZSTD_U8 only.
v1::BodyIndexFrame encode_body_index(const cv::Mat& body_index, v1::BodyIndexFrame::Encoding encoding,
                                     std::int64_t t_us, int zstd_level = 3);

// What a colour frame must be before any decoding: a known encoding, a size within
// kMaxColorPixels, and the file's header (PNG or JPEG) saying the chunk's width and height.
void check_color_header(const v1::ColorFrame& frame, const std::string& field = "color");
// Colour frame -> CV_8UC1 grey levels (the strap search, paper 1 II-I, needs brightness only),
// from JPEG or PNG, 8-bit grey or BGR; checks the size against the chunk's width and height.
cv::Mat decode_color_gray(const v1::ColorFrame& frame, const std::string& field = "color");
// An 8-bit grey or BGR image as a PNG colour frame.
v1::ColorFrame encode_color_png(const cv::Mat& image, std::int64_t t_us);

// Width and height read from an encoded file's header without decoding the pixels.
struct ImageSize {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
};
// PNG: the IHDR chunk. Throws kInvalidArgument naming `field` if the bytes are not a PNG.
ImageSize png_size(std::string_view bytes, const std::string& field);
// JPEG: the first start-of-frame marker. Throws kInvalidArgument if none is found.
ImageSize jpeg_size(std::string_view bytes, const std::string& field);

}  // namespace posefuse::session
