#include "session/color_image.hpp"

#include <algorithm>
#include <csetjmp>
#include <cstdio>  // jpeglib.h uses FILE without including it
#include <vector>

#include <jpeglib.h>

#include "common/error.hpp"
#include "session/image_codec.hpp"

namespace posefuse::session {

namespace {

// One libjpeg decompression with its error handler. Plain data owned by the caller, so that a
// longjmp out of libjpeg leaves nothing to destroy but the decompressor itself.
struct JpegDecoder {
  jpeg_decompress_struct info;
  jpeg_error_mgr errors;
  std::jmp_buf on_error;
  char message[JMSG_LENGTH_MAX];
};

[[noreturn]] void jump_to_caller(j_common_ptr info) {
  // `info` is the decoder's first member.
  JpegDecoder* decoder = reinterpret_cast<JpegDecoder*>(info);
  (*info->err->format_message)(info, decoder->message);
  std::longjmp(decoder->on_error, 1);
}

// libjpeg reports corrupt entropy data as a warning and decodes on (grey where data is missing),
// as OpenCV's decoder (decode_color_gray) also does: not printed, not an error.
void ignore_message(j_common_ptr, int) {}

// Where decoded rows go: the whole image's buffer, and the row ranges and the column range to
// decode (no rows: headers only).
struct RowsTarget {
  unsigned char* pixels = nullptr;  // row-major, `stride` bytes a row, the whole image's size
  std::size_t stride = 0;
  int col0 = 0, col1 = -1;
  std::span<const geometry::PixelRect> row_ranges;  // disjoint, ascending; only row0 and row1 used
};

// Reads the headers, starts the decompressor and decodes `target`'s rows over its columns (widened
// to whole blocks by libjpeg). Returns false with decoder.message set when libjpeg fails; width and
// height are what the decoder outputs.
bool decode_jpeg_rows(const std::string& bytes, const RowsTarget& target, JpegDecoder& decoder, int& width,
                      int& height) {
  decoder.info.err = jpeg_std_error(&decoder.errors);
  decoder.errors.error_exit = jump_to_caller;
  decoder.errors.emit_message = ignore_message;
  jpeg_create_decompress(&decoder.info);
  if (setjmp(decoder.on_error)) {
    jpeg_destroy_decompress(&decoder.info);
    return false;
  }
  jpeg_mem_src(&decoder.info, reinterpret_cast<const unsigned char*>(bytes.data()),
               static_cast<unsigned long>(bytes.size()));
  jpeg_read_header(&decoder.info, TRUE);
  decoder.info.out_color_space = JCS_GRAYSCALE;  // only the luma's blocks are transformed
  jpeg_start_decompress(&decoder.info);
  width = static_cast<int>(decoder.info.output_width);
  height = static_cast<int>(decoder.info.output_height);
  if (!target.row_ranges.empty()) {
    JDIMENSION col0 = static_cast<JDIMENSION>(target.col0);
    JDIMENSION cols = static_cast<JDIMENSION>(target.col1 - target.col0 + 1);
    jpeg_crop_scanline(&decoder.info, &col0, &cols);
    for (const geometry::PixelRect& range : target.row_ranges) {
      const auto row0 = static_cast<JDIMENSION>(range.row0), row1 = static_cast<JDIMENSION>(range.row1);
      if (decoder.info.output_scanline < row0) jpeg_skip_scanlines(&decoder.info, row0 - decoder.info.output_scanline);
      while (decoder.info.output_scanline <= row1) {
        JSAMPROW row = target.pixels + decoder.info.output_scanline * target.stride + col0;
        jpeg_read_scanlines(&decoder.info, &row, 1);
      }
    }
  }
  // The rows below the last range are not needed: destroying aborts the decompression.
  jpeg_destroy_decompress(&decoder.info);
  return true;
}

void decode_jpeg(const std::string& bytes, const RowsTarget& target, int expected_width, int expected_height,
                 const std::string& data_field) {
  JpegDecoder decoder{};
  int width = 0, height = 0;
  if (!decode_jpeg_rows(bytes, target, decoder, width, height)) {
    throw_invalid(data_field, std::string("JPEG cannot be decoded: ") + decoder.message);
  }
  if (width != expected_width || height != expected_height) {
    throw_invalid(data_field, "JPEG decodes to " + std::to_string(width) + "x" + std::to_string(height) +
                                  ", the chunk says " + std::to_string(expected_width) + "x" +
                                  std::to_string(expected_height));
  }
}

}  // namespace

ColorImage ColorImage::from_frame(const v1::ColorFrame& frame, const std::string& field) {
  ColorImage image;
  if (frame.encoding() == v1::ColorFrame::JPEG) {
    check_color_header(frame, field);
    decode_jpeg(frame.data(), RowsTarget{}, static_cast<int>(frame.width()), static_cast<int>(frame.height()),
                field + ".data");
    image.jpeg_ = std::make_shared<const std::string>(frame.data());
  } else {
    image.gray_ = decode_color_gray(frame, field);
  }
  image.width_ = static_cast<int>(frame.width());
  image.height_ = static_cast<int>(frame.height());
  return image;
}

std::size_t ColorImage::held_bytes() const { return jpeg_ ? jpeg_->size() : gray_.total() * gray_.elemSize(); }

void ColorImage::decode_gray(std::span<const geometry::PixelRect> rects, cv::Mat& gray,
                             const std::string& field) const {
  if (empty()) throw_invalid(field, "no colour image to decode");
  if (gray.rows != height_ || gray.cols != width_ || gray.type() != CV_8UC1 || !gray.isContinuous()) {
    gray.create(height_, width_, CV_8UC1);
    gray.setTo(0);
  }
  std::vector<geometry::PixelRect> clipped;
  for (const geometry::PixelRect& rect : rects) {
    const geometry::PixelRect c{std::max(rect.col0, 0), std::max(rect.row0, 0), std::min(rect.col1, width_ - 1),
                                std::min(rect.row1, height_ - 1)};
    if (!c.empty()) clipped.push_back(c);
  }
  if (clipped.empty()) return;
  if (!jpeg_) {
    for (const geometry::PixelRect& c : clipped) {
      const cv::Rect roi(c.col0, c.row0, c.col1 - c.col0 + 1, c.row1 - c.row0 + 1);
      gray_(roi).copyTo(gray(roi));
    }
    return;
  }
  // One pass: the columns from the leftmost to the rightmost rectangle, the union of their rows.
  RowsTarget target{gray.data, gray.step[0], width_, -1, {}};
  std::sort(clipped.begin(), clipped.end(), [](const auto& a, const auto& b) { return a.row0 < b.row0; });
  std::vector<geometry::PixelRect> row_ranges;
  for (const geometry::PixelRect& c : clipped) {
    target.col0 = std::min(target.col0, c.col0);
    target.col1 = std::max(target.col1, c.col1);
    if (!row_ranges.empty() && c.row0 <= row_ranges.back().row1 + 1) {
      row_ranges.back().row1 = std::max(row_ranges.back().row1, c.row1);
    } else {
      row_ranges.push_back(c);
    }
  }
  target.row_ranges = row_ranges;
  decode_jpeg(*jpeg_, target, width_, height_, field + ".data");
}

}  // namespace posefuse::session
