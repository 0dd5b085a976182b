#include "session/directory_reader.hpp"
#include "session/directory_writer.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "fixture.hpp"
#include "session/chunk_file.hpp"
#include "session/convert.hpp"
#include "session/directory_layout.hpp"
#include "session/image_codec.hpp"
#include "session/imu_batch.hpp"

namespace posefuse::session::testing {
namespace {

namespace fs = std::filesystem;

std::vector<SessionChunk> read_directory(const fs::path& directory) {
  DirectoryReader reader(directory);
  return read_all(reader);
}

void write_directory(const fs::path& directory, const std::vector<SessionChunk>& chunks) {
  DirectoryWriter writer(directory);
  for (const SessionChunk& c : chunks) writer.write(c);
  writer.finish();
}

std::string text_of(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void replace_text(const fs::path& path, const std::string& from, const std::string& to) {
  std::string text = text_of(path);
  const std::size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
}

TEST(Directory, ChunkFileToDirectoryToChunkFileIsExact) {
  TempDir dir;
  const auto session = make_session();
  write_chunk_file(dir / "in.pfchunks", session);
  EXPECT_EQ(chunk_file_to_directory(dir / "in.pfchunks", dir / "rec"), session.size());
  EXPECT_EQ(directory_to_chunk_file(dir / "rec", dir / "out.pfchunks"), session.size());
  expect_same_stream(session, read_chunk_file(dir / "out.pfchunks"));
  // And once more through a directory: the directory form is a fixed point too.
  EXPECT_EQ(chunk_file_to_directory(dir / "out.pfchunks", dir / "rec2"), session.size());
  expect_same_stream(session, read_directory(dir / "rec2"));
}

TEST(Directory, LayoutIsAsDocumented) {
  TempDir dir;
  write_directory(dir / "rec", make_session());
  for (const char* name :
       {"header.json", "end.json", "skeleton.csv", "sync_events.csv", "audio.wav", "audio_chunks.csv",
        "imu/wrist_l.csv", "imu/wrist_r.csv", "imu/base.csv", "depth/1000000.png", "depth/1066666.png",
        "body_index/1033333.png", "color/1001000.png", "color/1034333.jpg"}) {
    EXPECT_TRUE(fs::is_regular_file(dir / "rec" / name)) << name;
  }
  const std::string imu = text_of(dir / "rec/imu/wrist_l.csv");
  EXPECT_EQ(imu.substr(0, imu.find('\n')), "t_us,gx,gy,gz,ax,ay,az,mx,my,mz");
  EXPECT_EQ(std::count(imu.begin(), imu.end(), '\n'), 71);  // header + 70 samples
  const std::string skeleton = text_of(dir / "rec/skeleton.csv");
  EXPECT_EQ(std::count(skeleton.begin(), skeleton.end(), '\n'), 1 + 4 * 25);
  EXPECT_NE(text_of(dir / "rec/header.json").find("\"subject_id\": \"S-0042\""), std::string::npos);
  EXPECT_NE(text_of(dir / "rec/sync_events.csv").find("1050000,camera,OTHER,00ff2c37"), std::string::npos);
}

TEST(Directory, RawAndZstdDepthBecomePngWithTheSamePixels) {
  TempDir dir;
  auto session = make_session();
  const std::size_t raw = index_of(session, SessionChunk::kDepth, 0);
  const std::size_t zstd = index_of(session, SessionChunk::kDepth, 1);
  const std::size_t ids = index_of(session, SessionChunk::kBodyIndex, 0);
  const cv::Mat raw_pixels = decode_depth(session[raw].depth());
  const cv::Mat zstd_pixels = decode_depth(session[zstd].depth());
  const cv::Mat id_pixels = decode_body_index(session[ids].body_index());
  *session[raw].mutable_depth() = encode_depth(raw_pixels, v1::DepthFrame::RAW_U16_LE, session[raw].depth().t_us());
  *session[zstd].mutable_depth() = encode_depth(zstd_pixels, v1::DepthFrame::ZSTD_U16_LE, session[zstd].depth().t_us());
  *session[ids].mutable_body_index() =
      encode_body_index(id_pixels, v1::BodyIndexFrame::RAW_U8, session[ids].body_index().t_us());
  write_chunk_file(dir / "in", session);
  chunk_file_to_directory(dir / "in", dir / "rec");
  const auto back = read_directory(dir / "rec");
  ASSERT_EQ(back.size(), session.size());
  EXPECT_EQ(back[raw].depth().encoding(), v1::DepthFrame::PNG16);
  EXPECT_EQ(back[zstd].depth().encoding(), v1::DepthFrame::PNG16);
  EXPECT_EQ(back[ids].body_index().encoding(), v1::BodyIndexFrame::PNG8);
  EXPECT_EQ(cv::norm(decode_depth(back[raw].depth()), raw_pixels, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(decode_depth(back[zstd].depth()), zstd_pixels, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(decode_body_index(back[ids].body_index()), id_pixels, cv::NORM_INF), 0.0);
}

TEST(Directory, ImuBatchesAreRegroupedWithoutLosingSamples) {
  TempDir dir;
  auto session = make_session();
  // Merge the first device's batches into one 70-sample batch, as a recorder might send them.
  const std::string device = session[index_of(session, SessionChunk::kImu)].imu().device_id();
  std::vector<imu::ImuSample> all;
  std::vector<SessionChunk> merged;
  for (const SessionChunk& c : session) {
    if (c.has_imu() && c.imu().device_id() == device) {
      const auto part = samples_from_batch(c.imu());
      if (all.empty()) merged.emplace_back();  // placeholder at the first batch's position
      all.insert(all.end(), part.begin(), part.end());
    } else {
      merged.push_back(c);
    }
  }
  for (SessionChunk& c : merged) {
    if (c.chunk_case() == SessionChunk::CHUNK_NOT_SET) *c.mutable_imu() = batch_from_samples(device, all);
  }
  recount_end(merged);
  write_chunk_file(dir / "in", merged);
  chunk_file_to_directory(dir / "in", dir / "rec");
  // Reading the directory gives the canonical batching back: the fixture itself.
  expect_same_stream(session, read_directory(dir / "rec"));
}

TEST(Directory, MissingHeaderJson) {
  TempDir dir;
  write_directory(dir / "rec", make_session());
  fs::remove(dir / "rec/header.json");
  expect_error([&] { DirectoryReader reader(dir / "rec"); }, ErrorCode::kNotFound, "header.json");
}

TEST(Directory, MalformedHeaderJson) {
  TempDir dir;
  write_directory(dir / "rec", make_session());
  replace_text(dir / "rec/header.json", "\"subject_id\"", "\"subject_name\"");
  expect_error([&] { DirectoryReader reader(dir / "rec"); }, ErrorCode::kInvalidArgument, "header.json");
}

TEST(Directory, MissingEndJsonFailsConversion) {
  TempDir dir;
  write_directory(dir / "rec", make_session());
  fs::remove(dir / "rec/end.json");
  expect_error([&] { directory_to_chunk_file(dir / "rec", dir / "out"); }, ErrorCode::kInvalidArgument, "end");
}

TEST(Directory, BadCsvFieldsNameFileLineAndColumn) {
  TempDir dir;
  write_directory(dir / "rec", make_session());
  replace_text(dir / "rec/skeleton.csv", ",TRACKED,", ",TRACKD,");
  expect_error([&] { read_directory(dir / "rec"); }, ErrorCode::kInvalidArgument, "skeleton.csv:2:state");

  write_directory(dir / "rec2", make_session());
  replace_text(dir / "rec2/imu/base.csv", "\n1022500,", "\n1022500x,");
  expect_error([&] { read_directory(dir / "rec2"); }, ErrorCode::kInvalidArgument, "imu/base.csv:3:t_us");
}

TEST(Directory, NaNInImuCsvIsCaughtByTheConverter) {
  TempDir dir;
  write_directory(dir / "rec", make_session());
  // Line 3 of base.csv is sample 1 of the first base batch.
  std::string text = text_of(dir / "rec/imu/base.csv");
  const std::size_t line3 = text.find("\n1022500,") + 1;
  const std::size_t gx = text.find(',', line3) + 1;
  text.replace(gx, text.find(',', gx) - gx, "nan");
  std::ofstream(dir / "rec/imu/base.csv", std::ios::trunc) << text;
  const auto chunks = read_directory(dir / "rec");
  std::size_t base_batch = 0;
  while (!(chunks[base_batch].has_imu() && chunks[base_batch].imu().device_id() == "base")) ++base_batch;
  expect_error([&] { directory_to_chunk_file(dir / "rec", dir / "out"); }, ErrorCode::kInvalidArgument,
               "chunk[" + std::to_string(base_batch) + "].imu[1].gyr_rad_s");
}

TEST(Directory, WrongSizeDepthPngIsCaughtByTheConverter) {
  TempDir dir;
  write_directory(dir / "rec", make_session());
  const cv::Mat small(11, 16, CV_16UC1, cv::Scalar(1000));
  const auto frame = encode_depth(small, v1::DepthFrame::PNG16, 1033333);
  std::ofstream(dir / "rec/depth/1033333.png", std::ios::binary | std::ios::trunc) << frame.data();
  const auto chunks = read_directory(dir / "rec");
  const std::size_t i = index_of(chunks, SessionChunk::kDepth, 1);
  EXPECT_EQ(chunks[i].depth().height(), 11u);
  expect_error([&] { directory_to_chunk_file(dir / "rec", dir / "out"); }, ErrorCode::kInvalidArgument,
               "chunk[" + std::to_string(i) + "].depth.height");
}

TEST(Directory, FrameFileNamesMustBeTimestamps) {
  TempDir dir;
  write_directory(dir / "rec", make_session());
  fs::rename(dir / "rec/depth/1000000.png", dir / "rec/depth/first.png");
  expect_error([&] { DirectoryReader reader(dir / "rec"); }, ErrorCode::kInvalidArgument, "depth/first.png");
}

TEST(Directory, AudioNeedsItsChunkTable) {
  TempDir dir;
  write_directory(dir / "rec", make_session());
  fs::remove(dir / "rec/audio_chunks.csv");
  expect_error([&] { DirectoryReader reader(dir / "rec"); }, ErrorCode::kNotFound, "audio_chunks.csv");
}

TEST(Directory, ImuFileForUnknownDevice) {
  TempDir dir;
  write_directory(dir / "rec", make_session());
  fs::copy_file(dir / "rec/imu/base.csv", dir / "rec/imu/ankle.csv");
  expect_error([&] { DirectoryReader reader(dir / "rec"); }, ErrorCode::kInvalidArgument, "imu/ankle.csv");
}

TEST(Directory, WriterRefusesNonEmptyDirectory) {
  TempDir dir;
  write_directory(dir / "rec", make_session());
  expect_error([&] { DirectoryWriter writer(dir / "rec"); }, ErrorCode::kFailedPrecondition, (dir / "rec").string());
}

TEST(Directory, WriterNeedsHeaderFirst) {
  TempDir dir;
  const auto session = make_session();
  DirectoryWriter writer(dir / "rec");
  expect_error([&] { writer.write(session[1]); }, ErrorCode::kInvalidArgument, "chunk[0]");
}

}  // namespace
}  // namespace posefuse::session::testing
