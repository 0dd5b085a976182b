#pragma once
// Writes a session chunk stream as a recording directory (docs/recording-format.md).
//
// The writer trusts content checks to SessionValidator (the converters run it first); it checks
// only what it needs to write safely: header first, file-safe device ids, no two frames of one
// stream with the same t_us (they would share a file name).
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "session/chunk_stream.hpp"
#include "session/text_fields.hpp"
#include "session/wav.hpp"

namespace posefuse::session {

class DirectoryWriter : public ChunkSink {
 public:
  // Creates `directory`; kFailedPrecondition if it exists and is not empty.
  explicit DirectoryWriter(const std::filesystem::path& directory);

  void write(const SessionChunk& chunk) override;
  void finish() override;

 private:
  void write_header(const v1::SessionHeader& header);
  void write_depth(const v1::DepthFrame& frame);
  void write_body_index(const v1::BodyIndexFrame& frame);
  void write_color(const v1::ColorFrame& frame);
  void write_skeleton(const v1::SkeletonFrame& frame);
  void write_imu(const v1::ImuBatch& batch);
  void write_audio(const v1::AudioChunk& audio);
  void write_sync(const v1::SyncEvent& event);
  void write_end(const v1::EndOfSession& end);
  // Path of a new frame file; kInvalidArgument if it already exists.
  std::filesystem::path frame_path(const char* subdirectory, std::int64_t t_us, const char* ext);

  std::filesystem::path directory_;
  std::uint64_t index_ = 0;
  bool have_header_ = false;
  std::optional<CsvWriter> skeleton_;
  std::optional<CsvWriter> sync_events_;
  std::optional<CsvWriter> audio_chunks_;
  std::optional<WavWriter> audio_;
  std::map<std::string, std::unique_ptr<CsvWriter>> imu_;  // by device_id
};

}  // namespace posefuse::session
