#include "client/recording.hpp"

#include <cmath>
#include <utility>

#include "body/standing_height.hpp"
#include "common/error.hpp"
#include "common/number_text.hpp"
#include "session/directory_layout.hpp"
#include "session/directory_reader.hpp"
#include "session/file_bytes.hpp"
#include "session/json_message.hpp"
#include "session/text_fields.hpp"

namespace posefuse::client {

namespace {

// Chunks a directory will produce, from its end.json: header, end marker, every frame, event
// and audio chunk, and the IMU batches DirectoryReader makes. 0 when there is no end.json.
std::uint64_t expected_directory_chunks(const std::filesystem::path& directory) {
  const auto end_path = directory / session::layout::kEndJson;
  if (!std::filesystem::exists(end_path)) return 0;
  v1::EndOfSession end;
  session::message_from_json(session::read_file_bytes(end_path, session::layout::kEndJson), session::layout::kEndJson,
                             end);
  std::uint64_t chunks = 2 + end.depth_frames() + end.body_index_frames() + end.skeleton_frames() + end.color_frames() +
                         end.audio_chunks() + end.sync_events();
  const std::uint64_t per_batch = session::layout::kImuSamplesPerBatch;
  for (const auto& [device, samples] : end.imu_samples()) {
    chunks += (samples + per_batch - 1) / per_batch;
  }
  return chunks;
}

}  // namespace

Recording::Recording(const std::filesystem::path& path, HeaderEdits header_edits)
    : header_edits_(std::move(header_edits)) {
  if (!std::filesystem::exists(path)) {
    throw Error(ErrorCode::kNotFound, path.string(), "no such file or directory");
  }
  if (std::filesystem::is_directory(path)) {
    reader_ = std::make_unique<session::DirectoryReader>(path);
    expected_chunks_ = expected_directory_chunks(path);
  } else {
    auto file = std::make_unique<session::ChunkFileReader>(path);
    chunk_file_ = file.get();
    file_bytes_ = std::filesystem::file_size(path);
    reader_ = std::move(file);
  }
}

Recording::~Recording() = default;

bool Recording::next(session::SessionChunk& chunk) {
  if (!reader_->next(chunk)) return false;
  ++chunks_read_;
  if (chunk.has_header()) {
    v1::SessionHeader& header = *chunk.mutable_header();
    for (const auto& [key, value] : header_edits_.options) (*header.mutable_options())[key] = value;
    if (header_edits_.height_m) header.set_height_m(*header_edits_.height_m);
  }
  return true;
}

double Recording::fraction_read() const {
  if (chunk_file_ != nullptr) {
    return file_bytes_ == 0 ? 1.0 : static_cast<double>(chunk_file_->byte_offset()) / static_cast<double>(file_bytes_);
  }
  if (expected_chunks_ == 0) return -1.0;
  return std::min(1.0, static_cast<double>(chunks_read_) / static_cast<double>(expected_chunks_));
}

std::pair<std::string, std::string> parse_header_option(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw Error(ErrorCode::kInvalidArgument, "--option",
                "is '" + text + "', expected KEY=VALUE (e.g. fit.enabled=false)");
  }
  for (const unsigned char c : text) {
    if (c <= ' ' || c == 0x7f) {
      throw Error(ErrorCode::kInvalidArgument, "--option", "'" + text + "' has whitespace or a control character");
    }
  }
  return {text.substr(0, eq), text.substr(eq + 1)};
}

double parse_height_m(const std::string& text) {
  const double height_m = session::parse_double(text, "--height");
  const std::string range =
      fixed_text(body::kMinStandingHeightM, 1) + ".." + fixed_text(body::kMaxStandingHeightM, 1) + " m";
  if (std::isfinite(height_m) && height_m >= 100 * body::kMinStandingHeightM &&
      height_m <= 100 * body::kMaxStandingHeightM) {
    throw Error(ErrorCode::kInvalidArgument, "--height",
                "is " + text + ": the subject's standing height in metres (" + range + "), e.g. " +
                    fixed_text(height_m / 100, 2) + " for " + text + " cm");
  }
  if (!std::isfinite(height_m) || height_m < body::kMinStandingHeightM || height_m > body::kMaxStandingHeightM) {
    throw Error(ErrorCode::kInvalidArgument, "--height",
                "is " + text + ": the subject's standing height must be " + range);
  }
  return height_m;
}

}  // namespace posefuse::client
