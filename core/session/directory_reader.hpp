#pragma once
// Reads a recording directory (docs/recording-format.md) as one session chunk stream: the
// header, then every stream merged in chunk_order_key order, then the end marker if end.json
// exists. Streaming: frames are read one file at a time, CSV files one row at a time.
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "session/chunk_stream.hpp"
#include "session/recording_file.hpp"

namespace posefuse::session {

class DirectoryReader : public ChunkSource {
 public:
  // kNotFound when the directory or header.json is missing; kInvalidArgument when header.json
  // or a file name is malformed. Errors while reading name the file (and line for CSV).
  // Links in `directory` itself are followed (the caller chose it); inside it every file is
  // opened beneath it without following links, and only regular files are read
  // (recording_file.hpp). Device ids in header.json are checked before any file name is made
  // from them.
  explicit DirectoryReader(const std::filesystem::path& directory);
  // Reads an already open directory; `name` is what errors call it.
  DirectoryReader(UniqueFd directory, const std::string& name);
  ~DirectoryReader() override;

  bool next(SessionChunk& chunk) override;

  const v1::SessionHeader& header() const { return header_; }

 private:
  void refill(std::size_t stream);

  UniqueFd directory_;
  UniqueFd imu_folder_;  // open while the IMU streams read from it
  v1::SessionHeader header_;
  bool header_sent_ = false;
  bool end_sent_ = false;
  std::vector<std::unique_ptr<ChunkSource>> streams_;
  std::vector<std::optional<SessionChunk>> pending_;  // next chunk of each stream
};

}  // namespace posefuse::session
