#pragma once
// A recording on disk, read as a session chunk stream: a recording directory or a chunk file
// (docs/recording-format.md), with an estimate of how much of it has been read (for the
// progress line's ETA).
#include <cstdint>
#include <filesystem>
#include <memory>

#include "session/chunk_file.hpp"

namespace posefuse::client {

class Recording : public session::ChunkSource {
 public:
  // A directory is read with DirectoryReader, anything else as a chunk file. Throws
  // posefuse::Error (kNotFound, kInvalidArgument) naming the path.
  explicit Recording(const std::filesystem::path& path);
  ~Recording() override;

  bool next(session::SessionChunk& chunk) override;
  // Fraction 0..1 of the recording read so far; negative when unknown.
  double fraction_read() const;

 private:
  std::unique_ptr<session::ChunkSource> reader_;
  const session::ChunkFileReader* chunk_file_ = nullptr;  // when reading a chunk file
  std::uint64_t file_bytes_ = 0;
  std::uint64_t expected_chunks_ = 0;  // directory: from end.json; 0 = unknown
  std::uint64_t chunks_read_ = 0;
};

}  // namespace posefuse::client
