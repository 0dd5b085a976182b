// The image decoders (session/image_codec.*): depth RAW_U16_LE / PNG16 / ZSTD_U16_LE, body
// index RAW_U8 / PNG8 / ZSTD_U8, colour PNG / JPEG to grey (whole, and a rectangle as the strap
// search decodes it), and the PNG / JPEG header sniffers, under the
// limits they apply themselves (kMaxImageSide, kMaxDepthPixels, kMaxColorPixels).
//
// Input: byte 0 picks the decoder, byte 1 the encoding, bytes 2-3 and 4-5 the chunk's width
// and height (little-endian u16), the rest is the payload. A decoded image must have exactly
// the chunk's size and pixel type, whatever the payload claims.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "common/error.hpp"
#include "seeds.hpp"
#include "session/color_image.hpp"
#include "session/image_codec.hpp"

using namespace posefuse;

namespace {

enum Decoder : std::uint8_t { kDepth, kBodyIndex, kColor, kPngSize, kJpegSize, kDecoders };

std::string input(Decoder decoder, int encoding, std::uint16_t width, std::uint16_t height,
                  const std::string& payload) {
  std::string out{static_cast<char>(decoder),    static_cast<char>(encoding),      static_cast<char>(width & 0xFF),
                  static_cast<char>(width >> 8), static_cast<char>(height & 0xFF), static_cast<char>(height >> 8)};
  return out + payload;
}

void check(const cv::Mat& image, std::uint32_t width, std::uint32_t height, int type, const char* what) {
  if (image.empty() || static_cast<std::uint32_t>(image.cols) != width ||
      static_cast<std::uint32_t>(image.rows) != height || image.type() != type) {
    fuzz::invariant_failed(std::string(what) + ": decoded " + std::to_string(image.cols) + "x" +
                           std::to_string(image.rows) + " type " + std::to_string(image.type()) + ", the chunk says " +
                           std::to_string(width) + "x" + std::to_string(height));
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::init_harness([] {
    const cv::Mat depth = [] {
      cv::Mat m(6, 8, CV_16UC1);
      for (int i = 0; i < 48; ++i) m.at<std::uint16_t>(i / 8, i % 8) = static_cast<std::uint16_t>(1000 + 13 * i);
      return m;
    }();
    const cv::Mat ids(6, 8, CV_8UC1, cv::Scalar(1));
    fuzz::Seeds seeds;
    for (const auto e : {v1::DepthFrame::RAW_U16_LE, v1::DepthFrame::PNG16, v1::DepthFrame::ZSTD_U16_LE}) {
      seeds.push_back(
          {"depth-" + std::to_string(e), input(kDepth, e, 8, 6, session::encode_depth(depth, e, 0).data())});
    }
    for (const auto e : {v1::BodyIndexFrame::RAW_U8, v1::BodyIndexFrame::PNG8, v1::BodyIndexFrame::ZSTD_U8}) {
      seeds.push_back({"body-index-" + std::to_string(e),
                       input(kBodyIndex, e, 8, 6, session::encode_body_index(ids, e, 0).data())});
    }
    seeds.push_back(
        {"color-png-bgr", input(kColor, v1::ColorFrame::PNG, 8, 6, fuzz::encoded_image(8, 6, CV_8UC3, ".png"))});
    seeds.push_back(
        {"color-png-grey", input(kColor, v1::ColorFrame::PNG, 8, 6, fuzz::encoded_image(8, 6, CV_8UC1, ".png"))});
    seeds.push_back(
        {"color-jpeg-bgr", input(kColor, v1::ColorFrame::JPEG, 8, 6, fuzz::encoded_image(8, 6, CV_8UC3, ".jpg"))});
    seeds.push_back(
        {"color-jpeg-grey", input(kColor, v1::ColorFrame::JPEG, 16, 16, fuzz::encoded_image(16, 16, CV_8UC1, ".jpg"))});
    seeds.push_back({"png-size", input(kPngSize, 0, 0, 0, fuzz::encoded_image(8, 6, CV_16UC1, ".png"))});
    seeds.push_back({"jpeg-size", input(kJpegSize, 0, 0, 0, fuzz::encoded_image(8, 6, CV_8UC1, ".jpg"))});
    return seeds;
  });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 6) return 0;
  const auto decoder = static_cast<Decoder>(data[0] % kDecoders);
  const int encoding = data[1] % 5;  // also 0 (unspecified) and values no encoding has
  const std::uint32_t width = data[2] | (data[3] << 8);
  const std::uint32_t height = data[4] | (data[5] << 8);
  const std::string payload(reinterpret_cast<const char*>(data) + 6, size - 6);
  try {
    switch (decoder) {
      case kDepth: {
        v1::DepthFrame frame;
        frame.set_width(width);
        frame.set_height(height);
        frame.set_encoding(static_cast<v1::DepthFrame::Encoding>(encoding));
        frame.set_data(payload);
        check(session::decode_depth(frame), width, height, CV_16UC1, "depth");
        break;
      }
      case kBodyIndex: {
        v1::BodyIndexFrame frame;
        frame.set_width(width);
        frame.set_height(height);
        frame.set_encoding(static_cast<v1::BodyIndexFrame::Encoding>(encoding));
        frame.set_data(payload);
        check(session::decode_body_index(frame), width, height, CV_8UC1, "body_index");
        break;
      }
      case kColor: {
        v1::ColorFrame frame;
        frame.set_width(width);
        frame.set_height(height);
        frame.set_encoding(static_cast<v1::ColorFrame::Encoding>(encoding));
        frame.set_data(payload);
        // The strap search's decoder (session/color_image.hpp): a rectangle of the chunk's image.
        try {
          const session::ColorImage image = session::ColorImage::from_frame(frame);
          cv::Mat gray;
          const int w = static_cast<int>(width), h = static_cast<int>(height);
          image.decode_gray({w / 4, h / 3, w / 2 + 1, h / 2 + 1}, gray);
          check(gray, width, height, CV_8UC1, "color region");
        } catch (const Error&) {
        }
        check(session::decode_color_gray(frame), width, height, CV_8UC1, "color");
        break;
      }
      case kPngSize: {
        const session::ImageSize s = session::png_size(payload, "png");
        if (s.width == 0 || s.height == 0 || s.width > session::kMaxImageSide || s.height > session::kMaxImageSide) {
          fuzz::invariant_failed("png_size out of range");
        }
        break;
      }
      case kJpegSize: {
        const session::ImageSize s = session::jpeg_size(payload, "jpeg");
        if (s.width == 0 || s.height == 0) fuzz::invariant_failed("jpeg_size returned 0");
        break;
      }
      case kDecoders: break;
    }
  } catch (const Error&) {
  }
  return 0;
}
