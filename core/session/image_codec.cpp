#include "session/image_codec.hpp"

#include <bit>
#include <cstring>
#include <vector>

#include <zstd.h>
#include <opencv2/imgcodecs.hpp>

#include "common/error.hpp"

namespace posefuse::session {

namespace {

static_assert(std::endian::native == std::endian::little,
              "RAW_U16_LE payloads are copied as-is; a big-endian host needs a byte swap here");

void check_dimensions(std::uint32_t width, std::uint32_t height, std::uint64_t max_pixels, const std::string& field) {
  if (width == 0 || height == 0 || width > kMaxImageSide || height > kMaxImageSide) {
    throw_invalid(field + ".width", "image size " + std::to_string(width) + "x" + std::to_string(height) +
                                        " is outside 1.." + std::to_string(kMaxImageSide));
  }
  if (std::uint64_t{width} * height > max_pixels) {
    throw_invalid(field + ".width", "image size " + std::to_string(width) + "x" + std::to_string(height) +
                                        " has more than " + std::to_string(max_pixels) + " pixels");
  }
}

// IHDR after the size: bit depth (byte 24) and colour type (byte 25; 0 = greyscale).
struct PngFormat {
  int bit_depth = 0;
  int color_type = 0;
};
PngFormat png_format(std::string_view bytes) {
  if (bytes.size() < 26) return {};
  return {static_cast<unsigned char>(bytes[24]), static_cast<unsigned char>(bytes[25])};
}

std::string size_text(std::uint32_t width, std::uint32_t height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

void require_decoded_size(const cv::Mat& image, std::uint32_t width, std::uint32_t height,
                          const std::string& data_field) {
  if (static_cast<std::uint32_t>(image.cols) != width || static_cast<std::uint32_t>(image.rows) != height) {
    throw_invalid(data_field,
                  "decodes to " +
                      size_text(static_cast<std::uint32_t>(image.cols), static_cast<std::uint32_t>(image.rows)) +
                      ", the chunk says " + size_text(width, height));
  }
}

// Decodes a PNG payload and checks its type and size against the chunk's fields.
cv::Mat decode_png(const std::string& data, int expected_type, std::uint32_t width, std::uint32_t height,
                   const std::string& field) {
  const std::string data_field = field + ".data";
  // Reading the header first rejects non-PNG bytes and oversized images before any decoding.
  const ImageSize header = png_size(data, data_field);
  if (header.width != width || header.height != height) {
    throw_invalid(data_field,
                  "PNG is " + size_text(header.width, header.height) + ", the chunk says " + size_text(width, height));
  }
  // The pixel format too, before decoding: a 16-bit RGBA PNG of the right size would decode
  // to 8 bytes a pixel and only then be refused.
  const int bits = expected_type == CV_16UC1 ? 16 : 8;
  const PngFormat format = png_format(data);
  if (format.bit_depth != bits || format.color_type != 0) {
    throw_invalid(data_field, "PNG is not " + std::to_string(bits) + "-bit greyscale (bit depth " +
                                  std::to_string(format.bit_depth) + ", colour type " +
                                  std::to_string(format.color_type) + ")");
  }
  const cv::Mat encoded(1, static_cast<int>(data.size()), CV_8UC1, const_cast<char*>(data.data()));
  cv::Mat image = cv::imdecode(encoded, cv::IMREAD_UNCHANGED);
  if (image.empty()) throw_invalid(data_field, "PNG cannot be decoded");
  require_decoded_size(image, width, height, data_field);
  if (image.type() != expected_type) {
    throw_invalid(data_field, std::string("PNG has the wrong pixel type (expected ") +
                                  (expected_type == CV_16UC1 ? "16" : "8") + "-bit single channel)");
  }
  return image;
}

cv::Mat raw_to_mat(const std::string& data, int type, std::uint32_t width, std::uint32_t height,
                   const std::string& field, const char* encoding_name) {
  // The size first: nothing is allocated for a payload that does not match.
  const std::size_t expected = std::size_t{width} * height * CV_ELEM_SIZE(type);
  if (data.size() != expected) {
    throw_invalid(field + ".data", "has " + std::to_string(data.size()) + " bytes, expected " +
                                       std::to_string(expected) + " (" + size_text(width, height) + " " +
                                       encoding_name + ")");
  }
  cv::Mat image(static_cast<int>(height), static_cast<int>(width), type);
  std::memcpy(image.data, data.data(), expected);
  return image;
}

std::string encode_png(const cv::Mat& image) {
  std::vector<unsigned char> bytes;
  if (!cv::imencode(".png", image, bytes)) {
    throw Error(ErrorCode::kInternal, "png", "OpenCV could not encode the image");
  }
  return std::string(bytes.begin(), bytes.end());
}

std::string mat_bytes(const cv::Mat& image) {
  const cv::Mat contiguous = image.isContinuous() ? image : image.clone();
  return std::string(reinterpret_cast<const char*>(contiguous.data), contiguous.total() * contiguous.elemSize());
}

std::uint32_t read_be32(std::string_view bytes, std::size_t at) {
  std::uint32_t v = 0;
  for (std::size_t i = 0; i < 4; ++i) v = (v << 8) | static_cast<unsigned char>(bytes[at + i]);
  return v;
}

std::uint32_t read_be16(std::string_view bytes, std::size_t at) {
  return (static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[at])) << 8) |
         static_cast<unsigned char>(bytes[at + 1]);
}

// One zstd context of each kind per thread, reused across frames: creating one allocates and
// clears its tables (hundreds of KiB for compression), which costs more than a small frame.
template <typename Context, Context* (*create)(), std::size_t (*release)(Context*)>
Context* thread_context() {
  struct Owner {
    Context* context = create();
    ~Owner() { release(context); }
  };
  thread_local Owner owner;
  if (owner.context == nullptr) throw Error(ErrorCode::kInternal, "zstd", "cannot create a context");
  return owner.context;
}

ZSTD_DCtx* thread_decompression_context() { return thread_context<ZSTD_DCtx, ZSTD_createDCtx, ZSTD_freeDCtx>(); }

ZSTD_CCtx* thread_compression_context() { return thread_context<ZSTD_CCtx, ZSTD_createCCtx, ZSTD_freeCCtx>(); }

// Decompresses a zstd frame straight into a new width x height image of `type`. The frame's
// claimed content size is checked before anything is allocated, and the decoder never writes
// past the image, so hostile bytes cost at most one image.
cv::Mat zstd_to_mat(const std::string& data, int type, std::uint32_t width, std::uint32_t height,
                    const std::string& field, const char* encoding_name) {
  const std::size_t expected = std::size_t{width} * height * CV_ELEM_SIZE(type);
  const auto wrong_size = [&](unsigned long long got) {
    throw_invalid(field + ".data", "zstd content is " + std::to_string(got) + " bytes, expected " +
                                       std::to_string(expected) + " (" + size_text(width, height) + " " +
                                       encoding_name + ")");
  };
  const unsigned long long content = ZSTD_getFrameContentSize(data.data(), data.size());
  if (content == ZSTD_CONTENTSIZE_ERROR) throw_invalid(field + ".data", "is not a zstd frame");
  if (content != ZSTD_CONTENTSIZE_UNKNOWN && content != expected) wrong_size(content);
  cv::Mat image(static_cast<int>(height), static_cast<int>(width), type);
  const std::size_t got =
      ZSTD_decompressDCtx(thread_decompression_context(), image.data, expected, data.data(), data.size());
  if (ZSTD_isError(got)) throw_invalid(field + ".data", std::string("zstd: ") + ZSTD_getErrorName(got));
  if (got != expected) wrong_size(got);
  return image;
}

std::string mat_to_zstd(const cv::Mat& image, int level, const char* what) {
  const cv::Mat contiguous = image.isContinuous() ? image : image.clone();
  const std::size_t size = contiguous.total() * contiguous.elemSize();
  std::string packed(ZSTD_compressBound(size), '\0');
  const std::size_t written =
      ZSTD_compressCCtx(thread_compression_context(), packed.data(), packed.size(), contiguous.data, size, level);
  if (ZSTD_isError(written)) {
    throw Error(ErrorCode::kInternal, what, std::string("zstd: ") + ZSTD_getErrorName(written));
  }
  packed.resize(written);
  return packed;
}

}  // namespace

cv::Mat decode_depth(const v1::DepthFrame& frame, const std::string& field) {
  check_dimensions(frame.width(), frame.height(), kMaxDepthPixels, field);
  switch (frame.encoding()) {
    case v1::DepthFrame::RAW_U16_LE:
      return raw_to_mat(frame.data(), CV_16UC1, frame.width(), frame.height(), field, "RAW_U16_LE");
    case v1::DepthFrame::PNG16: return decode_png(frame.data(), CV_16UC1, frame.width(), frame.height(), field);
    case v1::DepthFrame::ZSTD_U16_LE:
      return zstd_to_mat(frame.data(), CV_16UC1, frame.width(), frame.height(), field, "ZSTD_U16_LE");
    default: throw_invalid(field + ".encoding", "unknown depth encoding " + std::to_string(frame.encoding()));
  }
}

v1::DepthFrame encode_depth(const cv::Mat& depth_mm, v1::DepthFrame::Encoding encoding, std::int64_t t_us,
                            int zstd_level) {
  if (depth_mm.type() != CV_16UC1) throw_invalid("depth_mm", "expected a CV_16UC1 image");
  v1::DepthFrame frame;
  frame.set_t_us(t_us);
  frame.set_width(static_cast<std::uint32_t>(depth_mm.cols));
  frame.set_height(static_cast<std::uint32_t>(depth_mm.rows));
  frame.set_encoding(encoding);
  switch (encoding) {
    case v1::DepthFrame::RAW_U16_LE: frame.set_data(mat_bytes(depth_mm)); break;
    case v1::DepthFrame::PNG16: frame.set_data(encode_png(depth_mm)); break;
    case v1::DepthFrame::ZSTD_U16_LE: frame.set_data(mat_to_zstd(depth_mm, zstd_level, "depth")); break;
    default: throw_invalid("encoding", "unknown depth encoding " + std::to_string(encoding));
  }
  return frame;
}

void check_color_header(const v1::ColorFrame& frame, const std::string& field) {
  check_dimensions(frame.width(), frame.height(), kMaxColorPixels, field);
  const std::string data_field = field + ".data";
  ImageSize header;
  switch (frame.encoding()) {
    case v1::ColorFrame::PNG: header = png_size(frame.data(), data_field); break;
    case v1::ColorFrame::JPEG: header = jpeg_size(frame.data(), data_field); break;
    default: throw_invalid(field + ".encoding", "unknown color encoding " + std::to_string(frame.encoding()));
  }
  if (header.width != frame.width() || header.height != frame.height()) {
    throw_invalid(data_field, "image is " + size_text(header.width, header.height) + ", the chunk says " +
                                  size_text(frame.width(), frame.height()));
  }
}

cv::Mat decode_color_gray(const v1::ColorFrame& frame, const std::string& field) {
  // The header first: rejects other bytes and oversized images before any decoding.
  check_color_header(frame, field);
  const std::string data_field = field + ".data";
  const cv::Mat encoded(1, static_cast<int>(frame.data().size()), CV_8UC1, const_cast<char*>(frame.data().data()));
  cv::Mat gray = cv::imdecode(encoded, cv::IMREAD_GRAYSCALE);
  if (gray.empty() || gray.type() != CV_8UC1) throw_invalid(data_field, "image cannot be decoded");
  // The decoder's own idea of the size must be the one checked above.
  require_decoded_size(gray, frame.width(), frame.height(), data_field);
  return gray;
}

v1::ColorFrame encode_color_png(const cv::Mat& image, std::int64_t t_us) {
  if (image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3)) {
    throw_invalid("color", "expected an 8-bit grey or BGR image");
  }
  v1::ColorFrame frame;
  frame.set_t_us(t_us);
  frame.set_width(static_cast<std::uint32_t>(image.cols));
  frame.set_height(static_cast<std::uint32_t>(image.rows));
  frame.set_encoding(v1::ColorFrame::PNG);
  frame.set_data(encode_png(image));
  return frame;
}

cv::Mat decode_body_index(const v1::BodyIndexFrame& frame, const std::string& field) {
  check_dimensions(frame.width(), frame.height(), kMaxDepthPixels, field);
  switch (frame.encoding()) {
    case v1::BodyIndexFrame::RAW_U8:
      return raw_to_mat(frame.data(), CV_8UC1, frame.width(), frame.height(), field, "RAW_U8");
    case v1::BodyIndexFrame::PNG8: return decode_png(frame.data(), CV_8UC1, frame.width(), frame.height(), field);
    case v1::BodyIndexFrame::ZSTD_U8:
      return zstd_to_mat(frame.data(), CV_8UC1, frame.width(), frame.height(), field, "ZSTD_U8");
    default: throw_invalid(field + ".encoding", "unknown body index encoding " + std::to_string(frame.encoding()));
  }
}

v1::BodyIndexFrame encode_body_index(const cv::Mat& body_index, v1::BodyIndexFrame::Encoding encoding,
                                     std::int64_t t_us, int zstd_level) {
  if (body_index.type() != CV_8UC1) throw_invalid("body_index", "expected a CV_8UC1 image");
  v1::BodyIndexFrame frame;
  frame.set_t_us(t_us);
  frame.set_width(static_cast<std::uint32_t>(body_index.cols));
  frame.set_height(static_cast<std::uint32_t>(body_index.rows));
  frame.set_encoding(encoding);
  switch (encoding) {
    case v1::BodyIndexFrame::RAW_U8: frame.set_data(mat_bytes(body_index)); break;
    case v1::BodyIndexFrame::PNG8: frame.set_data(encode_png(body_index)); break;
    case v1::BodyIndexFrame::ZSTD_U8: frame.set_data(mat_to_zstd(body_index, zstd_level, "body_index")); break;
    default: throw_invalid("encoding", "unknown body index encoding " + std::to_string(encoding));
  }
  return frame;
}

ImageSize png_size(std::string_view bytes, const std::string& field) {
  // 8-byte signature, then the IHDR chunk: length(4) "IHDR"(4) width(4) height(4).
  static constexpr std::string_view kSignature("\x89PNG\r\n\x1a\n", 8);
  if (bytes.size() < 24 || bytes.substr(0, 8) != kSignature || bytes.substr(12, 4) != "IHDR") {
    throw_invalid(field, "is not a PNG file");
  }
  const ImageSize size{read_be32(bytes, 16), read_be32(bytes, 20)};
  if (size.width == 0 || size.height == 0 || size.width > kMaxImageSide || size.height > kMaxImageSide) {
    throw_invalid(field,
                  "PNG size " + size_text(size.width, size.height) + " is outside 1.." + std::to_string(kMaxImageSide));
  }
  return size;
}

ImageSize jpeg_size(std::string_view bytes, const std::string& field) {
  if (bytes.size() < 4 || static_cast<unsigned char>(bytes[0]) != 0xFF ||
      static_cast<unsigned char>(bytes[1]) != 0xD8) {
    throw_invalid(field, "is not a JPEG file");
  }
  // Walk the marker segments (each FF xx LLLL ...) up to the first start-of-frame (SOF0..SOF15
  // except DHT C4, JPG C8, DAC CC), which holds precision(1) height(2) width(2). The walk must
  // see the frame header libjpeg decodes: RST0..RST7 (D0..D7) and TEM (01) are markers without
  // a length, as libjpeg reads them (taking the next two bytes as a length would jump over the
  // real frame header to a decoy one with a small size).
  std::size_t at = 2;
  while (at + 4 <= bytes.size()) {
    if (static_cast<unsigned char>(bytes[at]) != 0xFF) break;
    const auto marker = static_cast<unsigned char>(bytes[at + 1]);
    if (marker == 0xFF) {  // fill byte
      ++at;
      continue;
    }
    if (marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) {  // no length, no content
      at += 2;
      continue;
    }
    if (marker == 0xD8 || marker == 0xD9) break;  // a second SOI, or EOI before any frame
    const std::uint32_t length = read_be16(bytes, at + 2);
    const bool is_sof = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
    if (is_sof) {
      if (at + 9 > bytes.size()) break;
      const ImageSize size{read_be16(bytes, at + 7), read_be16(bytes, at + 5)};
      if (size.width == 0 || size.height == 0) break;
      return size;
    }
    if (marker == 0xDA || length < 2) break;  // start of scan before any frame header
    at += 2 + length;
  }
  throw_invalid(field, "JPEG has no readable frame header");
}

}  // namespace posefuse::session
