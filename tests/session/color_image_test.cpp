// A colour frame kept encoded and decoded over a rectangle (session/color_image.hpp): the pixels
// are the whole frame's decode's, bad frames are refused when they arrive, by name.
#include <gtest/gtest.h>

#include <cstdio>  // jpeglib.h uses FILE without including it
#include <random>
#include <vector>

#include <jpeglib.h>

#include <opencv2/imgcodecs.hpp>

#include "../imu/expect_error.hpp"
#include "session/color_image.hpp"
#include "session/image_codec.hpp"

namespace posefuse::session {
namespace {

using posefuse::testing::expect_error;

// Smooth shading, edges and noise, so that every block of the JPEG carries detail.
cv::Mat test_picture(int width, int height, int channels, std::uint64_t seed) {
  cv::Mat image(height, width, channels == 3 ? CV_8UC3 : CV_8UC1);
  std::mt19937_64 random(seed);
  std::normal_distribution<double> noise(0.0, 12.0);
  for (int r = 0; r < height; ++r)
    for (int c = 0; c < width; ++c)
      for (int k = 0; k < channels; ++k) {
        const double level = 60.0 + 0.8 * r + 0.6 * c + 40.0 * k + ((c / 9 + r / 7) % 2 ? 50.0 : 0.0) + noise(random);
        image.ptr<std::uint8_t>(r)[c * channels + k] = cv::saturate_cast<std::uint8_t>(level);
      }
  return image;
}

v1::ColorFrame jpeg_frame(const cv::Mat& image, std::vector<int> params = {cv::IMWRITE_JPEG_QUALITY, 90}) {
  std::vector<unsigned char> bytes;
  EXPECT_TRUE(cv::imencode(".jpg", image, bytes, params));
  v1::ColorFrame frame;
  frame.set_t_us(1000);
  frame.set_width(static_cast<std::uint32_t>(image.cols));
  frame.set_height(static_cast<std::uint32_t>(image.rows));
  frame.set_encoding(v1::ColorFrame::JPEG);
  frame.set_data(std::string(bytes.begin(), bytes.end()));
  return frame;
}

// Every pixel of `rect` (clipped) in `region` equals the whole frame's.
void expect_rect_equal(const cv::Mat& region, const cv::Mat& whole, const geometry::PixelRect& rect,
                       const std::string& what) {
  ASSERT_EQ(region.size(), whole.size()) << what;
  ASSERT_EQ(region.type(), CV_8UC1) << what;
  int differing = 0;
  for (int r = std::max(rect.row0, 0); r <= std::min(rect.row1, whole.rows - 1); ++r)
    for (int c = std::max(rect.col0, 0); c <= std::min(rect.col1, whole.cols - 1); ++c)
      differing += region.at<std::uint8_t>(r, c) != whole.at<std::uint8_t>(r, c);
  EXPECT_EQ(differing, 0) << what << " rect cols " << rect.col0 << ".." << rect.col1 << " rows " << rect.row0 << ".."
                          << rect.row1;
}

// Rectangles at the corners, on the edges, single pixels, the whole image and random ones.
std::vector<geometry::PixelRect> test_rects(int width, int height) {
  std::vector<geometry::PixelRect> rects = {{0, 0, width - 1, height - 1},
                                            {0, 0, 0, 0},
                                            {width - 1, height - 1, width - 1, height - 1},
                                            {5, 9, 5, 9},
                                            {17, 3, 40, 60},
                                            {width - 20, height - 13, width - 1, height - 1},
                                            {-10, -5, 12, 7},
                                            {0, height / 2, width - 1, height / 2}};
  std::mt19937_64 random(7);
  for (int i = 0; i < 30; ++i) {
    std::uniform_int_distribution<int> col(0, width - 1), row(0, height - 1);
    const int c0 = col(random), c1 = col(random), r0 = row(random), r1 = row(random);
    rects.push_back({std::min(c0, c1), std::min(r0, r1), std::max(c0, c1), std::max(r0, r1)});
  }
  return rects;
}

TEST(ColorImage, RectanglesDecodeAsTheWholeFrame) {
  // Sizes that are not whole blocks; colour (OpenCV's 4:2:0), grey, progressive, restart markers.
  struct Case {
    const char* name;
    int width, height, channels;
    std::vector<int> params;
  };
  const std::vector<Case> cases = {
      {"colour 4:2:0", 150, 110, 3, {cv::IMWRITE_JPEG_QUALITY, 90}},
      {"colour, odd size", 97, 61, 3, {cv::IMWRITE_JPEG_QUALITY, 95}},
      {"grey", 130, 75, 1, {cv::IMWRITE_JPEG_QUALITY, 80}},
      {"progressive", 120, 90, 3, {cv::IMWRITE_JPEG_QUALITY, 90, cv::IMWRITE_JPEG_PROGRESSIVE, 1}},
      {"restart markers", 144, 96, 3, {cv::IMWRITE_JPEG_QUALITY, 90, cv::IMWRITE_JPEG_RST_INTERVAL, 3}},
  };
  for (const Case& c : cases) {
    const v1::ColorFrame frame = jpeg_frame(test_picture(c.width, c.height, c.channels, 3), c.params);
    const cv::Mat whole = decode_color_gray(frame);
    const ColorImage image = ColorImage::from_frame(frame);
    EXPECT_EQ(image.width(), c.width);
    EXPECT_EQ(image.height(), c.height);
    EXPECT_EQ(image.held_bytes(), frame.data().size()) << c.name << ": kept encoded";
    for (const geometry::PixelRect& rect : test_rects(c.width, c.height)) {
      cv::Mat region;
      image.decode_gray(rect, region);
      expect_rect_equal(region, whole, rect, c.name);
    }
  }
}

TEST(ColorImage, SeveralRectanglesDecodeInOnePass) {
  // Both forearms: rectangles apart, overlapping, in any order, one outside the image.
  const v1::ColorFrame frame = jpeg_frame(test_picture(150, 110, 3, 9));
  const cv::Mat whole = decode_color_gray(frame);
  const ColorImage image = ColorImage::from_frame(frame);
  const std::vector<std::vector<geometry::PixelRect>> sets = {
      {{10, 60, 30, 90}, {110, 20, 140, 50}},
      {{110, 20, 140, 50}, {10, 60, 30, 90}},
      {{40, 10, 70, 40}, {60, 30, 90, 80}, {0, 100, 5, 109}},
      {{20, 20, 30, 30}, {200, 200, 210, 210}},
      {{5, 5, 6, 6}, {5, 7, 6, 8}},
  };
  for (const auto& rects : sets) {
    cv::Mat gray(110, 150, CV_8UC1, cv::Scalar(77));
    image.decode_gray(rects, gray);
    for (const geometry::PixelRect& rect : rects) expect_rect_equal(gray, whole, rect, "set");
    // Rows no rectangle covers are not written.
    for (int r = 0; r < gray.rows; ++r) {
      bool covered = false;
      for (const geometry::PixelRect& rect : rects) covered |= r >= rect.row0 && r <= rect.row1;
      if (!covered) {
        EXPECT_EQ(cv::countNonZero(gray.row(r) != 77), 0) << "row " << r;
      }
    }
  }
}

TEST(ColorImage, OnlyTheRectanglesRowsAreWritten) {
  // Columns are decoded in whole blocks, rows exactly: the rows outside keep what the buffer held.
  const v1::ColorFrame frame = jpeg_frame(test_picture(150, 110, 3, 4));
  const ColorImage image = ColorImage::from_frame(frame);
  cv::Mat gray(110, 150, CV_8UC1, cv::Scalar(77));
  image.decode_gray({30, 40, 60, 52}, gray);
  for (int r = 0; r < gray.rows; ++r) {
    if (r >= 40 && r <= 52) continue;
    EXPECT_EQ(cv::countNonZero(gray.row(r) != 77), 0) << "row " << r;
  }
  expect_rect_equal(gray, decode_color_gray(frame), {30, 40, 60, 52}, "after a prefilled buffer");
  // A buffer of another size is replaced by a zeroed one of the frame's.
  cv::Mat small(5, 5, CV_8UC1, cv::Scalar(77));
  image.decode_gray({0, 0, 3, 3}, small);
  EXPECT_EQ(small.size(), cv::Size(150, 110));
  EXPECT_EQ(small.at<std::uint8_t>(100, 140), 0);
  // A rectangle outside the image writes nothing.
  cv::Mat untouched = gray.clone();
  image.decode_gray({200, 0, 300, 10}, untouched);
  EXPECT_EQ(cv::norm(untouched, gray, cv::NORM_INF), 0.0);
}

TEST(ColorImage, PngFramesAreDecodedOnArrival) {
  const cv::Mat picture = test_picture(40, 30, 3, 5);
  const v1::ColorFrame frame = encode_color_png(picture, 2000);
  const ColorImage image = ColorImage::from_frame(frame);
  EXPECT_EQ(image.held_bytes(), 40u * 30u);
  const cv::Mat whole = decode_color_gray(frame);
  for (const geometry::PixelRect& rect : test_rects(40, 30)) {
    cv::Mat region;
    image.decode_gray(rect, region);
    expect_rect_equal(region, whole, rect, "png");
  }
}

TEST(ColorImage, RefusesBadFramesOnArrival) {
  const v1::ColorFrame good = jpeg_frame(test_picture(64, 48, 3, 6));
  v1::ColorFrame frame = good;
  frame.set_data("not a jpeg at all");
  expect_error([&] { ColorImage::from_frame(frame, "chunk[3].color"); }, ErrorCode::kInvalidArgument,
               "chunk[3].color.data");
  frame = good;
  frame.set_width(65);
  expect_error([&] { ColorImage::from_frame(frame); }, ErrorCode::kInvalidArgument, "color.data");
  frame = good;
  frame.set_encoding(static_cast<v1::ColorFrame::Encoding>(7));
  expect_error([&] { ColorImage::from_frame(frame); }, ErrorCode::kInvalidArgument, "color.encoding");
  frame = good;
  frame.set_width(0);
  expect_error([&] { ColorImage::from_frame(frame); }, ErrorCode::kInvalidArgument, "color.width");
  // Cut inside the tables, before the pixel data: libjpeg cannot start.
  const std::size_t scan = good.data().find("\xFF\xDA");
  ASSERT_NE(scan, std::string::npos);
  for (const std::size_t cut : {std::size_t{30}, scan / 2, scan - 10}) {
    frame = good;
    frame.set_data(good.data().substr(0, cut));
    expect_error([&] { ColorImage::from_frame(frame); }, ErrorCode::kInvalidArgument, "color.data");
  }
  // A quantisation table of an index JPEG does not have.
  frame = good;
  std::string bytes = good.data();
  const std::size_t dqt = bytes.find("\xFF\xDB");
  ASSERT_NE(dqt, std::string::npos);
  bytes[dqt + 4] = static_cast<char>(0x07);
  frame.set_data(bytes);
  expect_error([&] { ColorImage::from_frame(frame); }, ErrorCode::kInvalidArgument, "color.data");
}

// A 16 x 8 CMYK JPEG (a colour space libjpeg does not turn to grey).
std::string cmyk_jpeg() {
  jpeg_compress_struct info;
  jpeg_error_mgr errors;
  info.err = jpeg_std_error(&errors);
  jpeg_create_compress(&info);
  unsigned char* buffer = nullptr;
  unsigned long size = 0;
  jpeg_mem_dest(&info, &buffer, &size);
  info.image_width = 16;
  info.image_height = 8;
  info.input_components = 4;
  info.in_color_space = JCS_CMYK;
  jpeg_set_defaults(&info);
  jpeg_start_compress(&info, TRUE);
  std::vector<unsigned char> row(64);
  for (std::size_t i = 0; i < row.size(); ++i) row[i] = static_cast<unsigned char>(3 * i);
  for (int y = 0; y < 8; ++y) {
    JSAMPROW pointer = row.data();
    jpeg_write_scanlines(&info, &pointer, 1);
  }
  jpeg_finish_compress(&info);
  jpeg_destroy_compress(&info);
  std::string bytes(reinterpret_cast<const char*>(buffer), size);
  std::free(buffer);
  return bytes;
}

TEST(ColorImage, RefusesACmykJpegByName) {
  v1::ColorFrame frame;
  frame.set_width(16);
  frame.set_height(8);
  frame.set_encoding(v1::ColorFrame::JPEG);
  frame.set_data(cmyk_jpeg());
  try {
    ColorImage::from_frame(frame, "chunk[9].color");
    FAIL() << "a CMYK JPEG was accepted";
  } catch (const Error& error) {
    EXPECT_EQ(error.field(), "chunk[9].color.data");
    EXPECT_NE(std::string(error.what()).find("Unsupported color conversion"), std::string::npos) << error.what();
  }
}

TEST(ColorImage, CutPixelDataDecodesWhatIsThere) {
  // libjpeg takes missing pixel data as a warning and decodes on (here grey where data is
  // missing; OpenCV's decode_color_gray fills otherwise): every row the whole-frame decoder gets
  // right from the cut bytes the region decoder gets right too, and a rectangle is what the whole
  // image decoded this way holds there, never reading past the bytes.
  const v1::ColorFrame good = jpeg_frame(test_picture(150, 110, 3, 8));
  const cv::Mat truth = decode_color_gray(good);
  const std::size_t scan = good.data().find("\xFF\xDA");
  for (const double kept : {0.2, 0.5, 0.9}) {
    v1::ColorFrame frame = good;
    const auto cut = static_cast<std::size_t>(scan + kept * static_cast<double>(good.data().size() - scan));
    frame.set_data(good.data().substr(0, cut));
    const ColorImage image = ColorImage::from_frame(frame);
    const cv::Mat opencv = decode_color_gray(frame);
    cv::Mat whole;
    image.decode_gray({0, 0, 149, 109}, whole);
    int rows_right = 0;
    for (int r = 0; r < truth.rows; ++r) {
      if (cv::countNonZero(opencv.row(r) != truth.row(r)) > 0) continue;
      ++rows_right;
      EXPECT_EQ(cv::countNonZero(whole.row(r) != truth.row(r)), 0) << "kept " << kept << ", row " << r;
    }
    EXPECT_GT(rows_right, 0) << "kept " << kept;
    EXPECT_LT(rows_right, truth.rows) << "kept " << kept;
    for (const geometry::PixelRect& rect : test_rects(150, 110)) {
      cv::Mat region;
      image.decode_gray(rect, region);
      expect_rect_equal(region, whole, rect, "kept " + std::to_string(kept));
    }
  }
}

}  // namespace
}  // namespace posefuse::session
