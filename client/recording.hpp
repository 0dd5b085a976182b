#pragma once
// A recording on disk, read as a session chunk stream: a recording directory or a chunk file
// (docs/recording-format.md), with an estimate of how much of it has been read (for the
// progress line's ETA), and what the command line sets in its header (`--option KEY=VALUE`,
// `--height M`) put in on the way out, so that a recording needs no rewrite to change them.
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "session/chunk_file.hpp"

namespace posefuse::client {

// What the command line sets in a recording's header, replacing the recording's own values.
struct HeaderEdits {
  std::map<std::string, std::string> options;  // SessionHeader.options by key (`--option KEY=VALUE`)
  std::optional<double> height_m;              // SessionHeader.height_m (`--height M`)
};

class Recording : public session::ChunkSource {
 public:
  // A directory is read with DirectoryReader, anything else as a chunk file. Throws
  // posefuse::Error (kNotFound, kInvalidArgument) naming the path.
  explicit Recording(const std::filesystem::path& path, HeaderEdits header_edits = {});
  ~Recording() override;

  bool next(session::SessionChunk& chunk) override;
  // Fraction 0..1 of the recording read so far; negative when unknown.
  double fraction_read() const;

 private:
  std::unique_ptr<session::ChunkSource> reader_;
  HeaderEdits header_edits_;
  const session::ChunkFileReader* chunk_file_ = nullptr;  // when reading a chunk file
  std::uint64_t file_bytes_ = 0;
  std::uint64_t expected_chunks_ = 0;  // directory: from end.json; 0 = unknown
  std::uint64_t chunks_read_ = 0;
};

// "KEY=VALUE" of a `--option` flag as a (key, value) pair. Throws posefuse::Error naming
// `--option` when there is no '=', the key is empty or either side has whitespace or control
// characters (a key is a stage option name such as `fit.enabled`).
std::pair<std::string, std::string> parse_header_option(const std::string& text);

// The subject's standing height of a `--height` flag, in metres. Throws posefuse::Error naming
// `--height` when the text is not a number or lies outside the heights a header may record
// (body::kMinStandingHeightM..kMaxStandingHeightM); centimetres (e.g. 172) are refused by name.
double parse_height_m(const std::string& text);

}  // namespace posefuse::client
