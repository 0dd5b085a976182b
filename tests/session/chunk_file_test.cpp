#include "session/chunk_file.hpp"

#include <gtest/gtest.h>

#include <sys/resource.h>

#include <cstdint>
#include <fstream>

#include "fixture.hpp"

namespace posefuse::session::testing {
namespace {

std::string file_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void write_bytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

// Bytes a chunk takes in the file: varint length prefix plus payload.
std::size_t framed_size(const SessionChunk& chunk) {
  std::size_t size = chunk.ByteSizeLong();
  std::size_t prefix = 1;
  for (std::size_t rest = size >> 7; rest; rest >>= 7) ++prefix;
  return prefix + size;
}

TEST(ChunkFile, RoundTripsEveryChunkKind) {
  TempDir dir;
  const auto session = make_session();
  write_chunk_file(dir / "s.pfchunks", session);
  const auto back = read_chunk_file(dir / "s.pfchunks");
  expect_same_stream(session, back);
  EXPECT_NO_THROW(validate_all(back));
}

TEST(ChunkFile, MapFieldsAreWrittenInKeyOrder) {
  // Header options filled in opposite orders give the same bytes (a map's own iteration order
  // is random per instance).
  TempDir dir;
  SessionChunk forwards, backwards;
  for (int i = 0; i < 20; ++i) {
    (*forwards.mutable_header()->mutable_options())["key" + std::to_string(i)] = std::to_string(i);
    (*backwards.mutable_header()->mutable_options())["key" + std::to_string(19 - i)] = std::to_string(19 - i);
  }
  write_chunk_file(dir / "a.pfchunks", {forwards});
  write_chunk_file(dir / "b.pfchunks", {backwards});
  EXPECT_EQ(file_bytes(dir / "a.pfchunks"), file_bytes(dir / "b.pfchunks"));
}

TEST(ChunkFile, EmptyFileHasNoChunks) {
  TempDir dir;
  write_bytes(dir / "empty", "");
  EXPECT_TRUE(read_chunk_file(dir / "empty").empty());
}

TEST(ChunkFile, MissingFileIsNotFound) {
  TempDir dir;
  expect_error([&] { ChunkFileReader reader(dir / "nope"); }, ErrorCode::kNotFound, (dir / "nope").string());
}

TEST(ChunkFile, TruncatedPayloadIsDataLossNamingChunkAndOffset) {
  TempDir dir;
  const auto session = make_session();
  write_chunk_file(dir / "s", session);
  std::string bytes = file_bytes(dir / "s");
  // Offset where chunk 2 starts: header and chunk 1 framed.
  const std::size_t chunk2 = framed_size(session[0]) + framed_size(session[1]);
  bytes.resize(chunk2 + 10);  // inside chunk 2's payload
  write_bytes(dir / "cut", bytes);
  ChunkFileReader reader(dir / "cut");
  SessionChunk chunk;
  ASSERT_TRUE(reader.next(chunk));
  ASSERT_TRUE(reader.next(chunk));
  try {
    reader.next(chunk);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kDataLoss);
    EXPECT_EQ(e.field(), "chunk[2]");
    EXPECT_NE(std::string(e.what()).find("byte offset " + std::to_string(chunk2)), std::string::npos) << e.what();
  }
}

TEST(ChunkFile, TruncatedInsideLengthPrefixIsDataLoss) {
  TempDir dir;
  write_bytes(dir / "f", "\x85");  // continuation bit set, then end of file
  expect_error([&] { read_chunk_file(dir / "f"); }, ErrorCode::kDataLoss, "chunk[0]");
}

TEST(ChunkFile, CorruptVarintIsDataLoss) {
  TempDir dir;
  write_bytes(dir / "f", std::string(11, '\xff'));
  expect_error([&] { read_chunk_file(dir / "f"); }, ErrorCode::kDataLoss, "chunk[0]");
  // Ten bytes whose last one overflows 64 bits.
  write_bytes(dir / "g", std::string(9, '\xff') + "\x02");
  expect_error([&] { read_chunk_file(dir / "g"); }, ErrorCode::kDataLoss, "chunk[0]");
}

TEST(ChunkFile, OversizedLengthIsResourceExhausted) {
  TempDir dir;
  const auto session = make_session();
  write_chunk_file(dir / "s", session);
  // A length of 2^40 bytes after one good chunk: must fail before allocating anything.
  const std::string huge = "\x80\x80\x80\x80\x80\x20";
  write_bytes(dir / "f", file_bytes(dir / "s").substr(0, framed_size(session[0])) + huge);
  ChunkFileReader reader(dir / "f");
  SessionChunk chunk;
  ASSERT_TRUE(reader.next(chunk));
  ASSERT_TRUE(chunk.has_header());
  expect_error([&] { reader.next(chunk); }, ErrorCode::kResourceExhausted, "chunk[1]");
}

std::int64_t peak_rss_kib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;
}

// Found by fuzz/fuzz_chunk_file.cpp (with -malloc_limit_mb=16): a 181-byte file whose length
// prefix claimed 42 MB made the reader allocate (and zero) the whole claimed length before
// finding the file short. A file now costs what it holds.
TEST(ChunkFile, ShortFileClaimingAHugeChunkCostsWhatItHoldsNotWhatItClaims) {
  TempDir dir;
  // Length 2^26 - 1 (just under the 64 MiB limit), then 10 bytes.
  write_bytes(dir / "f", std::string("\xff\xff\xff\x1f") + std::string(10, 'x'));
  const std::int64_t before = peak_rss_kib();
  try {
    read_chunk_file(dir / "f");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kDataLoss);
    EXPECT_EQ(e.field(), "chunk[0]");
    EXPECT_NE(std::string(e.what()).find("expected 67108863 bytes, file has 10"), std::string::npos) << e.what();
  }
  // The peak resident size of this process (ctest runs each test alone) grew by far less than
  // the 64 MiB claimed: one read step (1 MiB) at most, plus noise.
  EXPECT_LT(peak_rss_kib() - before, 16 * 1024);
}

TEST(ChunkFile, LimitAppliesOnWriteAndReadToo) {
  TempDir dir;
  const auto session = make_session();
  const std::size_t depth = index_of(session, SessionChunk::kDepth);
  const std::uint64_t limit = session[depth].ByteSizeLong() - 1;
  const std::size_t sync = index_of(session, SessionChunk::kSyncEvent);
  ASSERT_LT(session[sync].ByteSizeLong(), limit);
  ChunkFileWriter writer(dir / "w", limit);
  writer.write(session[sync]);
  expect_error([&] { writer.write(session[depth]); }, ErrorCode::kResourceExhausted, "chunk[1]");

  write_chunk_file(dir / "s", {session[sync], session[depth]});
  ChunkFileReader reader(dir / "s", limit);
  SessionChunk chunk;
  ASSERT_TRUE(reader.next(chunk));
  expect_error([&] { reader.next(chunk); }, ErrorCode::kResourceExhausted, "chunk[1]");
}

TEST(ChunkFile, GarbagePayloadIsDataLoss) {
  TempDir dir;
  // Length 4, then bytes that are not a valid message (field 0 / bad wire type).
  write_bytes(dir / "f", std::string("\x04\x07\xff\xff\xff", 5));
  expect_error([&] { read_chunk_file(dir / "f"); }, ErrorCode::kDataLoss, "chunk[0]");
}

}  // namespace
}  // namespace posefuse::session::testing
