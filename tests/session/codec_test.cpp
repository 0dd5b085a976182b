// Payload codecs and small file formats: depth / body index images, IMU batches, WAV, CSV text.
#include <gtest/gtest.h>

#include <fstream>
#include <limits>

#include <opencv2/imgcodecs.hpp>

#include "fixture.hpp"
#include "session/image_codec.hpp"
#include "session/imu_batch.hpp"
#include "session/text_fields.hpp"
#include "session/wav.hpp"

namespace posefuse::session::testing {
namespace {

cv::Mat ramp_depth() {
  cv::Mat depth(12, 16, CV_16UC1);
  for (int r = 0; r < depth.rows; ++r) {
    for (int c = 0; c < depth.cols; ++c) depth.at<std::uint16_t>(r, c) = static_cast<std::uint16_t>(r * 4000 + c);
  }
  return depth;
}

TEST(DepthCodec, EveryEncodingRoundTrips) {
  const cv::Mat depth = ramp_depth();
  for (const auto encoding : {v1::DepthFrame::RAW_U16_LE, v1::DepthFrame::PNG16, v1::DepthFrame::ZSTD_U16_LE}) {
    const v1::DepthFrame frame = encode_depth(depth, encoding, 5);
    EXPECT_EQ(frame.width(), 16u);
    EXPECT_EQ(frame.height(), 12u);
    const cv::Mat back = decode_depth(frame);
    ASSERT_EQ(back.type(), CV_16UC1);
    EXPECT_EQ(cv::norm(back, depth, cv::NORM_INF), 0.0) << encoding;
  }
}

TEST(DepthCodec, RawIsLittleEndianRowMajor) {
  const v1::DepthFrame frame = encode_depth(ramp_depth(), v1::DepthFrame::RAW_U16_LE, 0);
  ASSERT_EQ(frame.data().size(), 16u * 12u * 2u);
  // Pixel (row 1, col 2) = 4002 = 0x0FA2.
  const std::size_t at = 2 * (1 * 16 + 2);
  EXPECT_EQ(static_cast<unsigned char>(frame.data()[at]), 0xA2);
  EXPECT_EQ(static_cast<unsigned char>(frame.data()[at + 1]), 0x0F);
}

TEST(DepthCodec, ZstdOfWrongSizeIsInvalid) {
  v1::DepthFrame frame = encode_depth(ramp_depth(), v1::DepthFrame::ZSTD_U16_LE, 0);
  frame.set_height(13);
  expect_error([&] { decode_depth(frame); }, ErrorCode::kInvalidArgument, "depth.data");
  frame.set_height(12);
  frame.set_data("not zstd");
  expect_error([&] { decode_depth(frame); }, ErrorCode::kInvalidArgument, "depth.data");
}

TEST(DepthCodec, HostileSizesAreRejectedBeforeAllocating) {
  v1::DepthFrame frame;
  frame.set_width(100000);
  frame.set_height(100000);
  frame.set_encoding(v1::DepthFrame::RAW_U16_LE);
  expect_error([&] { decode_depth(frame); }, ErrorCode::kInvalidArgument, "depth.width");
}

TEST(DepthCodec, FrameClaimingMorePixelsThanADepthCameraIsRejectedBeforeDecoding) {
  // A few KB that claim 8192 x 8192 u16 (128 MiB): refused on the claimed size alone, before
  // the payload is looked at (the payload here is not even zstd).
  v1::DepthFrame frame;
  frame.set_width(8192);
  frame.set_height(8192);
  frame.set_encoding(v1::DepthFrame::ZSTD_U16_LE);
  frame.set_data(std::string(4096, 'x'));
  expect_error([&] { decode_depth(frame); }, ErrorCode::kInvalidArgument, "depth.width");
  frame.set_width(1025);
  frame.set_height(1024);
  expect_error([&] { decode_depth(frame); }, ErrorCode::kInvalidArgument, "depth.width");
}

TEST(DepthCodec, PngOfTheRightSizeInAnotherPixelFormatIsRejectedByItsHeader) {
  const cv::Mat rgb16(12, 16, CV_16UC3, cv::Scalar(1, 2, 3));
  std::vector<unsigned char> png;
  ASSERT_TRUE(cv::imencode(".png", rgb16, png));
  v1::DepthFrame frame = encode_depth(ramp_depth(), v1::DepthFrame::PNG16, 0);
  frame.set_data(std::string(png.begin(), png.end()));
  try {
    decode_depth(frame);
    FAIL() << "a 16-bit RGB PNG was accepted as depth";
  } catch (const Error& error) {
    EXPECT_EQ(error.field(), "depth.data");
    // Refused by the IHDR (colour type 2 = RGB), not after decoding.
    EXPECT_NE(std::string(error.what()).find("colour type 2"), std::string::npos) << error.what();
  }
}

TEST(BodyIndexCodec, RoundTripsAndChecksPngType) {
  cv::Mat ids(12, 16, CV_8UC1, cv::Scalar(255));
  ids(cv::Rect(2, 2, 5, 5)).setTo(3);
  for (const auto encoding : {v1::BodyIndexFrame::RAW_U8, v1::BodyIndexFrame::PNG8, v1::BodyIndexFrame::ZSTD_U8}) {
    const cv::Mat back = decode_body_index(encode_body_index(ids, encoding, 0));
    ASSERT_EQ(back.type(), CV_8UC1) << encoding;
    EXPECT_EQ(cv::norm(back, ids, cv::NORM_INF), 0.0) << encoding;
  }
  // A 16-bit PNG is not a body index map.
  v1::BodyIndexFrame frame = encode_body_index(ids, v1::BodyIndexFrame::PNG8, 0);
  frame.set_data(encode_depth(ramp_depth(), v1::DepthFrame::PNG16, 0).data());
  expect_error([&] { decode_body_index(frame); }, ErrorCode::kInvalidArgument, "body_index.data");
}

TEST(BodyIndexCodec, ZstdOfWrongSizeIsInvalid) {
  const cv::Mat ids(12, 16, CV_8UC1, cv::Scalar(255));
  v1::BodyIndexFrame frame = encode_body_index(ids, v1::BodyIndexFrame::ZSTD_U8, 0);
  frame.set_height(13);
  expect_error([&] { decode_body_index(frame); }, ErrorCode::kInvalidArgument, "body_index.data");
  frame.set_height(12);
  frame.set_data("not zstd");
  expect_error([&] { decode_body_index(frame); }, ErrorCode::kInvalidArgument, "body_index.data");
  // Depth bytes of another size are not a body index map.
  frame.set_data(encode_depth(ramp_depth(), v1::DepthFrame::ZSTD_U16_LE, 0).data());
  expect_error([&] { decode_body_index(frame); }, ErrorCode::kInvalidArgument, "body_index.data");
}

// A zstd frame that does not state its content size (the format allows it): a header and
// `blocks` RLE blocks, each `run` copies of `value`, so a few bytes can stand for gigabytes.
std::string zstd_rle_frame(unsigned char value, int blocks, std::uint32_t run) {
  std::string bytes = "\x28\xB5\x2F\xFD";  // magic number
  bytes += '\x00';                         // no content size, no checksum, no dictionary
  bytes += '\x38';                         // window 2^(10 + 7) = 128 KiB, the largest block
  for (int b = 0; b < blocks; ++b) {
    const std::uint32_t header = (run << 3) | (1u << 1) | (b + 1 == blocks ? 1u : 0u);  // size, RLE, last
    bytes += static_cast<char>(header & 0xFF);
    bytes += static_cast<char>((header >> 8) & 0xFF);
    bytes += static_cast<char>((header >> 16) & 0xFF);
    bytes += static_cast<char>(value);
  }
  return bytes;
}

TEST(BodyIndexCodec, ZstdWithoutContentSizeIsBoundedByTheImage) {
  v1::BodyIndexFrame frame;
  frame.set_width(16);
  frame.set_height(12);
  frame.set_encoding(v1::BodyIndexFrame::ZSTD_U8);
  // Exactly the image: decodes (the hand-made frame is valid zstd).
  frame.set_data(zstd_rle_frame(3, 1, 16 * 12));
  const cv::Mat ids = decode_body_index(frame);
  ASSERT_EQ(ids.type(), CV_8UC1);
  EXPECT_EQ(cv::countNonZero(ids != 3), 0);
  // 8 KB standing for 256 MiB: refused once the image is full, not decompressed.
  frame.set_data(zstd_rle_frame(3, 2048, 128 * 1024));
  ASSERT_LT(frame.data().size(), 10'000u);
  expect_error([&] { decode_body_index(frame); }, ErrorCode::kInvalidArgument, "body_index.data");
  // Less than the image.
  frame.set_data(zstd_rle_frame(3, 1, 16 * 12 - 1));
  try {
    decode_body_index(frame);
    FAIL() << "a short zstd frame was accepted";
  } catch (const Error& error) {
    EXPECT_EQ(error.field(), "body_index.data");
    EXPECT_NE(std::string(error.what()).find("191 bytes, expected 192"), std::string::npos) << error.what();
  }
}

TEST(ImageSize, ReadsPngAndJpegHeaders) {
  const cv::Mat bgr(7, 9, CV_8UC3, cv::Scalar(1, 2, 3));
  std::vector<unsigned char> png, jpeg;
  cv::imencode(".png", bgr, png);
  cv::imencode(".jpg", bgr, jpeg);
  const ImageSize p = png_size(std::string(png.begin(), png.end()), "p");
  const ImageSize j = jpeg_size(std::string(jpeg.begin(), jpeg.end()), "j");
  EXPECT_EQ(p.width, 9u);
  EXPECT_EQ(p.height, 7u);
  EXPECT_EQ(j.width, 9u);
  EXPECT_EQ(j.height, 7u);
  expect_error([&] { jpeg_size(std::string(png.begin(), png.end()), "j"); }, ErrorCode::kInvalidArgument, "j");
  expect_error([&] { png_size("\x89PNG", "p"); }, ErrorCode::kInvalidArgument, "p");
}

// Found by fuzz/fuzz_image.cpp: a JPEG whose SOI is followed by RST0 (a marker without a
// length, which libjpeg skips) made jpeg_size take the next two bytes (FF E0, the APP0 marker)
// as a length and jump 65 KB ahead to a decoy frame header claiming 8x6, while libjpeg decoded
// the real 64x48 frame header: a colour frame's size check (and the pixel limit) was bypassed.
std::string jpeg_with_decoy_frame_header() {
  const cv::Mat grey(48, 64, CV_8UC1, cv::Scalar(90));
  std::vector<unsigned char> real;
  EXPECT_TRUE(cv::imencode(".jpg", grey, real));
  EXPECT_EQ(real[2], 0xFF);
  std::string bytes = "\xFF\xD8\xFF\xD0";      // SOI, RST0
  bytes.append(real.begin() + 2, real.end());  // the real JPEG after its SOI, up to its EOI
  const std::size_t decoy_at = 4 + ((std::size_t{0xFF} << 8) | real[3]);
  EXPECT_LT(bytes.size(), decoy_at);
  bytes.resize(decoy_at, '\0');
  // SOF0: length 11, precision 8, height 6, width 8, one component.
  bytes += std::string("\xFF\xC0\x00\x0B\x08\x00\x06\x00\x08\x01\x01\x11\x00", 13);
  return bytes;
}

TEST(ImageSize, JpegSizeIsTheFrameHeaderLibjpegDecodesNotADecoyBehindAMarkerWithoutLength) {
  const std::string jpeg = jpeg_with_decoy_frame_header();
  const ImageSize size = jpeg_size(jpeg, "j");
  EXPECT_EQ(size.width, 64u);
  EXPECT_EQ(size.height, 48u);

  v1::ColorFrame frame;
  frame.set_width(8);
  frame.set_height(6);
  frame.set_encoding(v1::ColorFrame::JPEG);
  frame.set_data(jpeg);
  expect_error([&] { decode_color_gray(frame); }, ErrorCode::kInvalidArgument, "color.data");
  // The frame it really is decodes.
  frame.set_width(64);
  frame.set_height(48);
  const cv::Mat gray = decode_color_gray(frame);
  EXPECT_EQ(gray.cols, 64);
  EXPECT_EQ(gray.rows, 48);
}

TEST(ImuBatchCodec, RoundTripsSamples) {
  std::vector<imu::ImuSample> samples(3);
  for (int i = 0; i < 3; ++i) {
    samples[i].t_us = 1000 + 12500 * i;
    samples[i].gyr_rad_s = {0.5 * i, -0.25, 1.0};
    samples[i].acc_m_s2 = {0.0, 0.125, 9.75};
    samples[i].mag_uT = {20.5, -3.0, -40.0 + i};
  }
  const v1::ImuBatch batch = batch_from_samples("wrist_l", samples);
  EXPECT_EQ(batch.device_id(), "wrist_l");
  ASSERT_EQ(batch.gyr_rad_s_size(), 9);
  EXPECT_EQ(batch.gyr_rad_s(3), 0.5f);  // sample 1 x: xyz interleaved
  const auto back = samples_from_batch(batch);
  ASSERT_EQ(back.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(back[i].t_us, samples[i].t_us);
    EXPECT_EQ(back[i].gyr_rad_s, samples[i].gyr_rad_s);
    EXPECT_EQ(back[i].acc_m_s2, samples[i].acc_m_s2);
    EXPECT_EQ(back[i].mag_uT, samples[i].mag_uT);
  }
}

TEST(ImuBatchCodec, EmptyOrMismatchedBatch) {
  expect_error([&] { samples_from_batch(v1::ImuBatch()); }, ErrorCode::kInvalidArgument, "imu.t_us");
  v1::ImuBatch batch = batch_from_samples("b", std::vector<imu::ImuSample>(2));
  batch.mutable_mag_ut()->RemoveLast();
  expect_error([&] { samples_from_batch(batch); }, ErrorCode::kInvalidArgument, "imu.mag_uT");
}

TEST(Wav, RoundTripsAndSkipsUnknownChunks) {
  TempDir dir;
  std::string pcm;
  for (int i = 0; i < 10; ++i) pcm += std::string{static_cast<char>(i), static_cast<char>(-i)};
  {
    WavWriter writer(dir / "a.wav", {48000, 2});
    writer.write_frames(pcm.substr(0, 8));
    writer.write_frames(pcm.substr(8));
    writer.finish();
  }
  WavReader reader(dir / "a.wav", "a.wav");
  EXPECT_EQ(reader.format().sample_rate_hz, 48000u);
  EXPECT_EQ(reader.format().channels, 2);
  EXPECT_EQ(reader.total_frames(), 5u);
  const std::string first = reader.read_frames(2);
  EXPECT_EQ(first + reader.read_frames(3), pcm);
  expect_error([&] { reader.read_frames(1); }, ErrorCode::kDataLoss, "a.wav.data");

  // Insert an odd-sized LIST chunk before "data", as some recorders do.
  std::ifstream in(dir / "a.wav", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  bytes.insert(36, std::string("LIST\x03\x00\x00\x00"
                               "abc\x00",
                               12));
  std::ofstream(dir / "b.wav", std::ios::binary) << bytes;
  WavReader with_list(dir / "b.wav", "b.wav");
  EXPECT_EQ(with_list.read_frames(5), pcm);
}

TEST(Wav, TruncatedOrNotPcm) {
  TempDir dir;
  {
    WavWriter writer(dir / "a.wav", {16000, 1});
    writer.write_frames(std::string(200, '\x01'));
    writer.finish();
  }
  std::ifstream in(dir / "a.wav", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  std::ofstream(dir / "cut.wav", std::ios::binary) << bytes.substr(0, bytes.size() - 10);
  expect_error([&] { WavReader r(dir / "cut.wav", "cut.wav"); }, ErrorCode::kDataLoss, "cut.wav.data");
  bytes[34] = 8;  // 8 bits per sample
  std::ofstream(dir / "u8.wav", std::ios::binary) << bytes;
  expect_error([&] { WavReader r(dir / "u8.wav", "u8.wav"); }, ErrorCode::kInvalidArgument, "u8.wav.fmt");
}

TEST(TextFields, NumbersRoundTripExactly) {
  for (const double v : {0.1, -1e-300, 1.0 / 3.0, 6.02214076e23}) {
    EXPECT_EQ(parse_double(format_double(v), "v"), v);
  }
  for (const float v : {0.1f, 9.81f, -3.4e38f}) EXPECT_EQ(parse_float(format_float(v), "v"), v);
  EXPECT_TRUE(std::isnan(parse_float(format_float(std::numeric_limits<float>::quiet_NaN()), "v")));
  EXPECT_EQ(parse_int64("-42", "v"), -42);
  expect_error([&] { parse_int64("12x", "f"); }, ErrorCode::kInvalidArgument, "f");
  expect_error([&] { parse_double("", "f"); }, ErrorCode::kInvalidArgument, "f");
  expect_error([&] { parse_uint64("-1", "f"); }, ErrorCode::kInvalidArgument, "f");
  EXPECT_EQ(from_hex(to_hex(std::string("\x00\xff\x10", 3)), "h"), std::string("\x00\xff\x10", 3));
  expect_error([&] { from_hex("0g", "h"); }, ErrorCode::kInvalidArgument, "h");
}

}  // namespace
}  // namespace posefuse::session::testing
