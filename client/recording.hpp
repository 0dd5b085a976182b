#pragma once
// A recording on disk, read as a session chunk stream: a recording directory or a chunk file
// (docs/recording-format.md), with an estimate of how much of it has been read (for the
// progress line's ETA), and stage options set on the command line (`--option KEY=VALUE`) put
// into its header on the way out, so that a recording needs no rewrite to change a stage option.
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <utility>

#include "session/chunk_file.hpp"

namespace posefuse::client {

class Recording : public session::ChunkSource {
 public:
  // A directory is read with DirectoryReader, anything else as a chunk file. Throws
  // posefuse::Error (kNotFound, kInvalidArgument) naming the path.
  // `header_options` are set in SessionHeader.options, replacing the recording's own values.
  explicit Recording(const std::filesystem::path& path, std::map<std::string, std::string> header_options = {});
  ~Recording() override;

  bool next(session::SessionChunk& chunk) override;
  // Fraction 0..1 of the recording read so far; negative when unknown.
  double fraction_read() const;

 private:
  std::unique_ptr<session::ChunkSource> reader_;
  std::map<std::string, std::string> header_options_;
  const session::ChunkFileReader* chunk_file_ = nullptr;  // when reading a chunk file
  std::uint64_t file_bytes_ = 0;
  std::uint64_t expected_chunks_ = 0;  // directory: from end.json; 0 = unknown
  std::uint64_t chunks_read_ = 0;
};

// "KEY=VALUE" of a `--option` flag as a (key, value) pair. Throws posefuse::Error naming
// `--option` when there is no '=', the key is empty or either side has whitespace or control
// characters (a key is a stage option name such as `fit.enabled`).
std::pair<std::string, std::string> parse_header_option(const std::string& text);

}  // namespace posefuse::client
