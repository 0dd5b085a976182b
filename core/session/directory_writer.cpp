#include "session/directory_writer.hpp"

#include "common/error.hpp"
#include "session/directory_layout.hpp"
#include "session/file_bytes.hpp"
#include "session/image_codec.hpp"
#include "session/json_message.hpp"
#include "session/session_validator.hpp"

namespace posefuse::session {

namespace fs = std::filesystem;

namespace {

void make_directory(const fs::path& path) {
  std::error_code ec;
  fs::create_directories(path, ec);
  if (ec) throw_precondition(path.string(), "cannot create directory: " + ec.message());
}

}  // namespace

DirectoryWriter::DirectoryWriter(const fs::path& directory) : directory_(directory) {
  std::error_code ec;
  if (fs::exists(directory, ec) && !fs::is_empty(directory, ec)) {
    throw_precondition(directory.string(), "exists and is not empty; refusing to mix recordings");
  }
  make_directory(directory);
}

void DirectoryWriter::write(const SessionChunk& chunk) {
  const std::string field = "chunk[" + std::to_string(index_) + "]";
  if (!have_header_ && !chunk.has_header()) throw_invalid(field, "expected the header first");
  switch (chunk.chunk_case()) {
    case SessionChunk::kHeader:
      if (have_header_) throw_invalid(field + ".header", "a second header");
      write_header(chunk.header());
      break;
    case SessionChunk::kDepth: write_depth(chunk.depth()); break;
    case SessionChunk::kBodyIndex: write_body_index(chunk.body_index()); break;
    case SessionChunk::kColor: write_color(chunk.color()); break;
    case SessionChunk::kSkeleton: write_skeleton(chunk.skeleton()); break;
    case SessionChunk::kImu: write_imu(chunk.imu()); break;
    case SessionChunk::kAudio: write_audio(chunk.audio()); break;
    case SessionChunk::kSyncEvent: write_sync(chunk.sync_event()); break;
    case SessionChunk::kEnd: write_end(chunk.end()); break;
    case SessionChunk::CHUNK_NOT_SET: throw_invalid(field, "is empty (no chunk kind set)");
  }
  ++index_;
}

void DirectoryWriter::finish() {
  if (skeleton_) skeleton_->close();
  if (sync_events_) sync_events_->close();
  if (audio_chunks_) audio_chunks_->close();
  if (audio_) audio_->finish();
  for (auto& [id, csv] : imu_) csv->close();
}

void DirectoryWriter::write_header(const v1::SessionHeader& header) {
  for (int i = 0; i < header.imu_devices_size(); ++i) {
    if (!is_valid_device_id(header.imu_devices(i).device_id())) {
      throw_invalid(
          "header.imu_devices[" + std::to_string(i) + "].device_id",
          "'" + header.imu_devices(i).device_id() + "' must match [A-Za-z0-9_.-]{1,64} (it becomes a file name)");
    }
  }
  write_file_bytes(directory_ / layout::kHeaderJson, message_to_json(header));
  have_header_ = true;
}

fs::path DirectoryWriter::frame_path(const char* subdirectory, std::int64_t t_us, const char* ext) {
  const fs::path folder = directory_ / subdirectory;
  make_directory(folder);
  fs::path path = folder / (std::to_string(t_us) + ext);
  if (fs::exists(path)) {
    throw_invalid("chunk[" + std::to_string(index_) + "]." + subdirectory + ".t_us",
                  "a second frame at " + std::to_string(t_us) + " us");
  }
  return path;
}

void DirectoryWriter::write_depth(const v1::DepthFrame& frame) {
  const fs::path path = frame_path(layout::kDepthDir, frame.t_us(), ".png");
  // PNG payloads are stored byte for byte; other encodings are re-encoded as 16-bit PNG.
  if (frame.encoding() == v1::DepthFrame::PNG16) {
    write_file_bytes(path, frame.data());
  } else {
    const cv::Mat depth = decode_depth(frame, "chunk[" + std::to_string(index_) + "].depth");
    write_file_bytes(path, encode_depth(depth, v1::DepthFrame::PNG16, frame.t_us()).data());
  }
}

void DirectoryWriter::write_body_index(const v1::BodyIndexFrame& frame) {
  const fs::path path = frame_path(layout::kBodyIndexDir, frame.t_us(), ".png");
  if (frame.encoding() == v1::BodyIndexFrame::PNG8) {
    write_file_bytes(path, frame.data());
  } else {
    const cv::Mat ids = decode_body_index(frame, "chunk[" + std::to_string(index_) + "].body_index");
    write_file_bytes(path, encode_body_index(ids, v1::BodyIndexFrame::PNG8, frame.t_us()).data());
  }
}

void DirectoryWriter::write_color(const v1::ColorFrame& frame) {
  const char* ext = nullptr;
  if (frame.encoding() == v1::ColorFrame::JPEG) ext = ".jpg";
  if (frame.encoding() == v1::ColorFrame::PNG) ext = ".png";
  if (!ext) {
    throw_invalid("chunk[" + std::to_string(index_) + "].color.encoding",
                  "unknown color encoding " + std::to_string(frame.encoding()));
  }
  write_file_bytes(frame_path(layout::kColorDir, frame.t_us(), ext), frame.data());
}

void DirectoryWriter::write_skeleton(const v1::SkeletonFrame& frame) {
  if (!skeleton_) skeleton_.emplace(directory_ / layout::kSkeletonCsv, layout::kSkeletonColumns);
  for (int j = 0; j < frame.joints_size(); ++j) {
    const v1::SkeletonJoint& joint = frame.joints(j);
    const std::string& state = v1::SkeletonJoint::State_Name(joint.state());
    if (state.empty() || j >= static_cast<int>(layout::kKinectJointNames.size())) {
      throw_invalid("chunk[" + std::to_string(index_) + "].skeleton.joints[" + std::to_string(j) + "]",
                    "joint index or state out of range; validate the stream first");
    }
    skeleton_->row({std::to_string(frame.t_us()), std::to_string(frame.body_id()), std::to_string(j),
                    layout::kKinectJointNames[static_cast<std::size_t>(j)], state,
                    format_double(joint.position_m().x()), format_double(joint.position_m().y()),
                    format_double(joint.position_m().z()), format_double(joint.orientation().w()),
                    format_double(joint.orientation().x()), format_double(joint.orientation().y()),
                    format_double(joint.orientation().z())});
  }
}

void DirectoryWriter::write_imu(const v1::ImuBatch& batch) {
  const std::string field = "chunk[" + std::to_string(index_) + "].imu";
  if (!is_valid_device_id(batch.device_id())) {
    throw_invalid(field + ".device_id", "'" + batch.device_id() + "' is not a valid device id");
  }
  const int n = batch.t_us_size();
  if (batch.gyr_rad_s_size() != 3 * n || batch.acc_m_s2_size() != 3 * n || batch.mag_ut_size() != 3 * n) {
    throw_invalid(field, "array sizes do not match t_us; validate the stream first");
  }
  auto& csv = imu_[batch.device_id()];
  if (!csv) {
    make_directory(directory_ / layout::kImuDir);
    csv = std::make_unique<CsvWriter>(directory_ / layout::kImuDir / (batch.device_id() + ".csv"), layout::kImuColumns);
  }
  std::vector<std::string> row(layout::kImuColumns.size());
  for (int i = 0; i < n; ++i) {
    row[0] = std::to_string(batch.t_us(i));
    for (int k = 0; k < 3; ++k) {
      row[1 + k] = format_float(batch.gyr_rad_s(3 * i + k));
      row[4 + k] = format_float(batch.acc_m_s2(3 * i + k));
      row[7 + k] = format_float(batch.mag_ut(3 * i + k));
    }
    csv->row(row);
  }
}

void DirectoryWriter::write_audio(const v1::AudioChunk& audio) {
  const std::string field = "chunk[" + std::to_string(index_) + "].audio";
  if (!audio_) {
    audio_.emplace(directory_ / layout::kAudioWav,
                   WavFormat{audio.sample_rate_hz(), static_cast<std::uint16_t>(audio.channels())});
    audio_chunks_.emplace(directory_ / layout::kAudioChunksCsv, layout::kAudioChunkColumns);
  }
  if (audio.sample_rate_hz() != audio_->format().sample_rate_hz || audio.channels() != audio_->format().channels) {
    throw_invalid(field, "sample rate or channel count differs from the first audio chunk");
  }
  audio_->write_frames(audio.pcm_s16le());
  audio_chunks_->row(
      {std::to_string(audio.t_us()), std::to_string(audio.pcm_s16le().size() / (2u * audio.channels()))});
}

void DirectoryWriter::write_sync(const v1::SyncEvent& event) {
  const std::string& kind = v1::SyncEvent::Kind_Name(event.kind());
  if (kind.empty() || event.device_id().find(',') != std::string::npos) {
    throw_invalid("chunk[" + std::to_string(index_) + "].sync_event",
                  "unknown kind or a comma in device_id; validate the stream first");
  }
  if (!sync_events_) {
    sync_events_.emplace(directory_ / layout::kSyncEventsCsv, layout::kSyncEventColumns);
  }
  sync_events_->row({std::to_string(event.t_us()), event.device_id(), kind, to_hex(event.payload())});
}

void DirectoryWriter::write_end(const v1::EndOfSession& end) {
  write_file_bytes(directory_ / layout::kEndJson, message_to_json(end));
}

}  // namespace posefuse::session
