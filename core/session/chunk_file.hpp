#pragma once
// The chunk file: SessionChunks in protobuf's length-delimited form, one after another
// (base-128 varint byte count, then that many bytes of the serialised chunk). See
// docs/recording-format.md. Reading is streaming: one chunk in memory at a time.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "session/chunk_stream.hpp"
#include "session/recording_file.hpp"

namespace posefuse::session {

// Largest serialised chunk accepted (64 MiB): far above a raw 1920x1080 color or 512x424 depth
// frame, small enough that a corrupt length cannot make us allocate gigabytes.
inline constexpr std::uint64_t kMaxChunkBytes = 64ull << 20;

class ChunkFileReader : public ChunkSource {
 public:
  // Throws kNotFound when the file cannot be opened, kInvalidArgument when it is not a regular
  // file (a FIFO would block every read).
  explicit ChunkFileReader(const std::filesystem::path& path, std::uint64_t max_chunk_bytes = kMaxChunkBytes);
  // Reads an already open file; `name` is what errors call it. Regular files only, as above.
  ChunkFileReader(UniqueFd file, const std::string& name, std::uint64_t max_chunk_bytes = kMaxChunkBytes);

  // False at a clean end of file (between chunks). Errors name "chunk[i]" and the byte offset
  // where chunk i starts: kDataLoss for a truncated or corrupt chunk, kResourceExhausted for a
  // length above max_chunk_bytes.
  bool next(SessionChunk& chunk) override;

  std::uint64_t chunks_read() const { return chunks_read_; }
  std::uint64_t byte_offset() const { return offset_; }

 private:
  std::unique_ptr<std::istream> in_;
  std::uint64_t max_chunk_bytes_;
  std::uint64_t chunks_read_ = 0;
  std::uint64_t offset_ = 0;
  std::string buffer_;
};

class ChunkFileWriter : public ChunkSink {
 public:
  // Creates or truncates the file; kFailedPrecondition when it cannot be created.
  explicit ChunkFileWriter(const std::filesystem::path& path, std::uint64_t max_chunk_bytes = kMaxChunkBytes);

  // kResourceExhausted when the chunk is larger than max_chunk_bytes (nothing is written).
  void write(const SessionChunk& chunk) override;
  void finish() override;

  std::uint64_t chunks_written() const { return chunks_written_; }

 private:
  std::filesystem::path path_;
  std::ofstream out_;
  std::uint64_t max_chunk_bytes_;
  std::uint64_t chunks_written_ = 0;
  std::string buffer_;
};

}  // namespace posefuse::session
