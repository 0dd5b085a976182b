#pragma once
// A tiny but complete session made in code for the session tests: every chunk kind, canonical
// order (as DirectoryReader yields it), so that the round trips must reproduce it exactly.
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "posefuse/v1/session.pb.h"
#include "session/chunk_stream.hpp"

namespace posefuse::session::testing {

using v1::SessionChunk;

// Header, 3 depth + 3 body index frames (16x12), 4 skeleton frames (two bodies), 2 color frames
// (PNG and JPEG), 3 IMU devices x 70 samples in canonical batches, 3 audio chunks, 3 sync
// events, and the end marker with matching counts.
std::vector<SessionChunk> make_session();

// Position of the n-th (0-based) chunk of `kind` in `chunks`.
std::size_t index_of(const std::vector<SessionChunk>& chunks, SessionChunk::ChunkCase kind, int n = 0);

// Recomputes the end marker of `chunks` (last chunk) after a test changed the stream.
void recount_end(std::vector<SessionChunk>& chunks);

// Runs SessionValidator over every chunk and finish().
void validate_all(const std::vector<SessionChunk>& chunks);

// Every chunk of a source, read to the end.
std::vector<SessionChunk> read_all(ChunkSource& source);

void write_chunk_file(const std::filesystem::path& path, const std::vector<SessionChunk>& chunks);
std::vector<SessionChunk> read_chunk_file(const std::filesystem::path& path);

// Asserts that `action` throws posefuse::Error with this code and field.
void expect_error(const std::function<void()>& action, ErrorCode code, const std::string& field);

// Asserts the two streams are equal chunk by chunk (names the first differing chunk).
void expect_same_stream(const std::vector<SessionChunk>& expected, const std::vector<SessionChunk>& actual);

// A fresh empty directory, removed with everything in it on destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

}  // namespace posefuse::session::testing
