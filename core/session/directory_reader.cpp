#include "session/directory_reader.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <set>

#include "common/error.hpp"
#include "session/chunk_file.hpp"
#include "session/chunk_order.hpp"
#include "session/directory_layout.hpp"
#include "session/image_codec.hpp"
#include "session/json_message.hpp"
#include "session/recording_file.hpp"
#include "session/session_validator.hpp"
#include "session/text_fields.hpp"
#include "session/wav.hpp"

namespace posefuse::session {

namespace fs = std::filesystem;

namespace {

enum class FrameKind { kDepth, kBodyIndex, kColor };

// depth/, body_index/ or color/: one file per frame named <t_us>.<ext>, read in t_us order.
class FrameFolderStream : public ChunkSource {
 public:
  FrameFolderStream(int recording, const char* folder_name, FrameKind kind)
      : folder_(open_beneath(recording, folder_name, folder_name)), kind_(kind) {
    require_directory(folder_.get(), folder_name);
    for (const std::string& file : list_directory(folder_.get(), folder_name)) {
      if (file.starts_with(".")) continue;  // editor and OS droppings
      const std::string name = std::string(folder_name) + "/" + file;
      const std::string ext = fs::path(file).extension().string();
      const bool ext_ok = ext == ".png" || (kind == FrameKind::kColor && (ext == ".jpg" || ext == ".jpeg"));
      if (!ext_ok) {
        throw_invalid(name, kind == FrameKind::kColor ? "expected files named <t_us>.jpg or <t_us>.png"
                                                      : "expected files named <t_us>.png");
      }
      if (entry_kind(folder_.get(), file) != FileKind::kRegular) {
        throw_invalid(name, "is not a regular file (links, FIFOs and devices are refused)");
      }
      const std::int64_t t_us = parse_int64(fs::path(file).stem().string(), name);
      files_.push_back({t_us, file, name});
    }
    std::sort(files_.begin(), files_.end(), [](const File& a, const File& b) { return a.t_us < b.t_us; });
    for (std::size_t i = 1; i < files_.size(); ++i) {
      if (files_[i].t_us == files_[i - 1].t_us) {
        throw_invalid(files_[i].name, "two frames at " + std::to_string(files_[i].t_us) + " us");
      }
    }
  }

  bool next(SessionChunk& chunk) override {
    if (next_ == files_.size()) return false;
    const File& file = files_[next_++];
    const UniqueFd opened = open_beneath(folder_.get(), file.entry, file.name);
    require_regular_file(opened.get(), file.name);
    // A frame file can be no larger than a chunk of the chunk-file form.
    std::string bytes = read_all(opened.get(), file.name, kMaxChunkBytes);
    chunk.Clear();
    const bool jpeg = kind_ == FrameKind::kColor && fs::path(file.entry).extension() != ".png";
    // The size comes from the file's header before the bytes move into the chunk.
    const ImageSize size = jpeg ? jpeg_size(bytes, file.name) : png_size(bytes, file.name);
    if (kind_ == FrameKind::kDepth) {
      fill(chunk.mutable_depth(), file.t_us, size, v1::DepthFrame::PNG16, std::move(bytes));
    } else if (kind_ == FrameKind::kBodyIndex) {
      fill(chunk.mutable_body_index(), file.t_us, size, v1::BodyIndexFrame::PNG8, std::move(bytes));
    } else {
      fill(chunk.mutable_color(), file.t_us, size, jpeg ? v1::ColorFrame::JPEG : v1::ColorFrame::PNG, std::move(bytes));
    }
    return true;
  }

 private:
  // DepthFrame, BodyIndexFrame and ColorFrame share these fields.
  template <typename Frame>
  static void fill(Frame* frame, std::int64_t t_us, ImageSize size, typename Frame::Encoding encoding,
                   std::string bytes) {
    frame->set_t_us(t_us);
    frame->set_width(size.width);
    frame->set_height(size.height);
    frame->set_encoding(encoding);
    frame->set_data(std::move(bytes));
  }

  struct File {
    std::int64_t t_us;
    std::string entry;  // the name inside the folder
    std::string name;   // folder/entry, for errors
  };
  UniqueFd folder_;
  FrameKind kind_;
  std::vector<File> files_;
  std::size_t next_ = 0;
};

// skeleton.csv: one row per joint; consecutive rows with the same (t_us, body_id) form a frame.
class SkeletonStream : public ChunkSource {
 public:
  explicit SkeletonStream(int recording)
      : csv_(open_stream_beneath(recording, layout::kSkeletonCsv), layout::kSkeletonCsv, layout::kSkeletonColumns) {
    have_row_ = csv_.next();
  }

  bool next(SessionChunk& chunk) override {
    if (!have_row_) return false;
    chunk.Clear();
    v1::SkeletonFrame* frame = chunk.mutable_skeleton();
    frame->set_t_us(parse_int64(csv_.at(0), csv_.field(0)));
    const std::uint64_t body_id = parse_uint64(csv_.at(1), csv_.field(1));
    if (body_id > 0xFFFFFFFFu) throw_invalid(csv_.field(1), "body id is too large");
    frame->set_body_id(static_cast<std::uint32_t>(body_id));
    while (have_row_ && parse_int64(csv_.at(0), csv_.field(0)) == frame->t_us() &&
           parse_uint64(csv_.at(1), csv_.field(1)) == body_id) {
      add_joint(*frame);
      have_row_ = csv_.next();
    }
    return true;
  }

 private:
  void add_joint(v1::SkeletonFrame& frame) {
    const std::uint64_t index = parse_uint64(csv_.at(2), csv_.field(2));
    const auto expected = static_cast<std::uint64_t>(frame.joints_size());
    if (index != expected) {
      throw_invalid(csv_.field(2), "joint " + std::to_string(index) + " where joint " + std::to_string(expected) +
                                       " was expected (rows of a frame list joints 0..24 in order)");
    }
    if (index >= layout::kKinectJointNames.size()) {
      throw_invalid(csv_.field(2), "a frame has more than 25 joints");
    }
    if (csv_.at(3) != layout::kKinectJointNames[index]) {
      throw_invalid(csv_.field(3), quoted(csv_.at(3)) + " but joint " + std::to_string(index) + " is " +
                                       layout::kKinectJointNames[index]);
    }
    v1::SkeletonJoint* joint = frame.add_joints();
    v1::SkeletonJoint::State state{};
    if (!v1::SkeletonJoint::State_Parse(std::string(csv_.at(4)), &state)) {
      throw_invalid(csv_.field(4), quoted(csv_.at(4)) + " is not NOT_TRACKED, INFERRED or TRACKED");
    }
    joint->set_state(state);
    // An all-zero vector or quaternion is left unset: proto3 reads an unset message as all
    // zeros anyway, and leaving it unset makes directory -> chunks -> directory exact.
    const double p[3] = {number(5), number(6), number(7)};
    if (p[0] != 0 || p[1] != 0 || p[2] != 0) {
      joint->mutable_position_m()->set_x(p[0]);
      joint->mutable_position_m()->set_y(p[1]);
      joint->mutable_position_m()->set_z(p[2]);
    }
    const double q[4] = {number(8), number(9), number(10), number(11)};
    if (q[0] != 0 || q[1] != 0 || q[2] != 0 || q[3] != 0) {
      joint->mutable_orientation()->set_w(q[0]);
      joint->mutable_orientation()->set_x(q[1]);
      joint->mutable_orientation()->set_y(q[2]);
      joint->mutable_orientation()->set_z(q[3]);
    }
  }

  double number(std::size_t column) const { return parse_double(csv_.at(column), csv_.field(column)); }

  CsvReader csv_;
  bool have_row_ = false;
};

// imu/<device_id>.csv: samples, grouped into batches of kImuSamplesPerBatch rows.
class ImuStream : public ChunkSource {
 public:
  // `imu_folder` is the open imu/ folder; `device_id` has passed is_valid_device_id.
  ImuStream(int imu_folder, std::string device_id)
      : csv_(open_stream_beneath(imu_folder, device_id + ".csv"),
             std::string(layout::kImuDir) + "/" + device_id + ".csv", layout::kImuColumns),
        device_id_(std::move(device_id)) {}

  bool next(SessionChunk& chunk) override {
    chunk.Clear();
    v1::ImuBatch* batch = chunk.mutable_imu();
    batch->set_device_id(device_id_);
    while (batch->t_us_size() < layout::kImuSamplesPerBatch && csv_.next()) {
      batch->add_t_us(parse_int64(csv_.at(0), csv_.field(0)));
      for (int k = 0; k < 3; ++k) {
        batch->add_gyr_rad_s(parse_float(csv_.at(1 + k), csv_.field(1 + k)));
        batch->add_acc_m_s2(parse_float(csv_.at(4 + k), csv_.field(4 + k)));
        batch->add_mag_ut(parse_float(csv_.at(7 + k), csv_.field(7 + k)));
      }
    }
    return batch->t_us_size() > 0;
  }

 private:
  CsvReader csv_;
  std::string device_id_;
};

// audio.wav cut into chunks by audio_chunks.csv (t_us of each chunk's first frame, frame count).
class AudioStream : public ChunkSource {
 public:
  explicit AudioStream(int recording)
      : wav_(open_wav(recording)),
        csv_(open_stream_beneath(recording, layout::kAudioChunksCsv), layout::kAudioChunksCsv,
             layout::kAudioChunkColumns) {}

  bool next(SessionChunk& chunk) override {
    if (!csv_.next()) {
      if (wav_.frames_left() > 0) {
        throw_invalid(layout::kAudioChunksCsv, "covers " + std::to_string(wav_.total_frames() - wav_.frames_left()) +
                                                   " sample frames, audio.wav has " +
                                                   std::to_string(wav_.total_frames()));
      }
      return false;
    }
    chunk.Clear();
    v1::AudioChunk* audio = chunk.mutable_audio();
    audio->set_t_us(parse_int64(csv_.at(0), csv_.field(0)));
    const std::uint64_t frames = parse_uint64(csv_.at(1), csv_.field(1));
    if (frames > wav_.frames_left()) {
      throw_invalid(csv_.field(1), std::to_string(frames) + " sample frames, but audio.wav has only " +
                                       std::to_string(wav_.frames_left()) + " left");
    }
    audio->set_sample_rate_hz(wav_.format().sample_rate_hz);
    audio->set_channels(wav_.format().channels);
    audio->set_pcm_s16le(wav_.read_frames(frames));
    return true;
  }

 private:
  static WavReader open_wav(int recording) {
    UniqueFd file = open_beneath(recording, layout::kAudioWav, layout::kAudioWav);
    require_regular_file(file.get(), layout::kAudioWav);
    struct stat status {};
    const std::uint64_t size = ::fstat(file.get(), &status) == 0 ? static_cast<std::uint64_t>(status.st_size) : 0;
    return WavReader(std::make_unique<FdInputStream>(std::move(file)), size, layout::kAudioWav);
  }

  WavReader wav_;
  CsvReader csv_;
};

// sync_events.csv: one event per row.
class SyncEventStream : public ChunkSource {
 public:
  explicit SyncEventStream(int recording)
      : csv_(open_stream_beneath(recording, layout::kSyncEventsCsv), layout::kSyncEventsCsv,
             layout::kSyncEventColumns) {}

  bool next(SessionChunk& chunk) override {
    if (!csv_.next()) return false;
    chunk.Clear();
    v1::SyncEvent* event = chunk.mutable_sync_event();
    event->set_t_us(parse_int64(csv_.at(0), csv_.field(0)));
    event->set_device_id(std::string(csv_.at(1)));
    v1::SyncEvent::Kind kind{};
    if (!v1::SyncEvent::Kind_Parse(std::string(csv_.at(2)), &kind)) {
      throw_invalid(csv_.field(2), quoted(csv_.at(2)) + " is not BUZZER_STOP, BLE_BROADCAST_RECEIPT or OTHER");
    }
    event->set_kind(kind);
    event->set_payload(from_hex(csv_.at(3), csv_.field(3)));
    return true;
  }

 private:
  CsvReader csv_;
};

// header.json and end.json are small; anything larger is not one.
constexpr std::uint64_t kMaxJsonBytes = 1u << 20;

std::string read_json_file(int recording, const char* name) {
  const UniqueFd file = open_beneath(recording, name, name);
  require_regular_file(file.get(), name);
  return read_all(file.get(), name, kMaxJsonBytes);
}

}  // namespace

DirectoryReader::DirectoryReader(const fs::path& directory)
    : DirectoryReader(open_path(directory, directory.string()), directory.string()) {}

DirectoryReader::DirectoryReader(UniqueFd directory, const std::string& name) : directory_(std::move(directory)) {
  if (file_kind(directory_.get()) != FileKind::kDirectory) {
    throw Error(ErrorCode::kNotFound, name, "is not a recording directory");
  }
  const int recording = directory_.get();
  if (entry_kind(recording, layout::kHeaderJson) == FileKind::kMissing) {
    throw Error(ErrorCode::kNotFound, layout::kHeaderJson,
                "missing in " + name + "; every recording directory has one");
  }
  message_from_json(read_json_file(recording, layout::kHeaderJson), layout::kHeaderJson, header_);
  // Device ids become file names (imu/<device_id>.csv): each is checked before any path is
  // built from it. The id is not quoted: it could be anything.
  for (int i = 0; i < header_.imu_devices_size(); ++i) {
    if (!is_valid_device_id(header_.imu_devices(i).device_id())) {
      throw_invalid(std::string(layout::kHeaderJson) + ".imu_devices[" + std::to_string(i) + "].device_id",
                    "must match [A-Za-z0-9_.-]{1,64} and not be '.' or '..'");
    }
  }

  if (has_entry(recording, layout::kDepthDir, FileKind::kDirectory)) {
    streams_.push_back(std::make_unique<FrameFolderStream>(recording, layout::kDepthDir, FrameKind::kDepth));
  }
  if (has_entry(recording, layout::kBodyIndexDir, FileKind::kDirectory)) {
    streams_.push_back(std::make_unique<FrameFolderStream>(recording, layout::kBodyIndexDir, FrameKind::kBodyIndex));
  }
  if (has_entry(recording, layout::kSkeletonCsv, FileKind::kRegular)) {
    streams_.push_back(std::make_unique<SkeletonStream>(recording));
  }
  if (has_entry(recording, layout::kColorDir, FileKind::kDirectory)) {
    streams_.push_back(std::make_unique<FrameFolderStream>(recording, layout::kColorDir, FrameKind::kColor));
  }
  if (has_entry(recording, layout::kImuDir, FileKind::kDirectory)) {
    imu_folder_ = open_beneath(recording, layout::kImuDir, layout::kImuDir);
    require_directory(imu_folder_.get(), layout::kImuDir);
    std::set<std::string> known;
    for (const v1::ImuDevice& device : header_.imu_devices()) known.insert(device.device_id());
    for (const std::string& file : list_directory(imu_folder_.get(), layout::kImuDir)) {
      if (file.starts_with(".")) continue;
      const std::string device_id = fs::path(file).stem().string();
      if (fs::path(file).extension() != ".csv" || !known.contains(device_id)) {
        throw_invalid(std::string(layout::kImuDir) + "/" + file,
                      "expected <device_id>.csv for a device listed in header.json imu_devices");
      }
    }
    for (const v1::ImuDevice& device : header_.imu_devices()) {
      const std::string file = device.device_id() + ".csv";
      if (has_entry(imu_folder_.get(), file, FileKind::kRegular)) {
        streams_.push_back(std::make_unique<ImuStream>(imu_folder_.get(), device.device_id()));
      }
    }
  }
  const bool has_wav = has_entry(recording, layout::kAudioWav, FileKind::kRegular);
  const bool has_audio_chunks = has_entry(recording, layout::kAudioChunksCsv, FileKind::kRegular);
  if (has_wav != has_audio_chunks) {
    throw Error(ErrorCode::kNotFound, has_wav ? layout::kAudioChunksCsv : layout::kAudioWav,
                std::string("missing; audio.wav and audio_chunks.csv come together"));
  }
  if (has_wav) streams_.push_back(std::make_unique<AudioStream>(recording));
  if (has_entry(recording, layout::kSyncEventsCsv, FileKind::kRegular)) {
    streams_.push_back(std::make_unique<SyncEventStream>(recording));
  }
  pending_.resize(streams_.size());
  for (std::size_t i = 0; i < streams_.size(); ++i) refill(i);
}

DirectoryReader::~DirectoryReader() = default;

void DirectoryReader::refill(std::size_t stream) {
  SessionChunk chunk;
  if (streams_[stream]->next(chunk)) {
    pending_[stream] = std::move(chunk);
  } else {
    pending_[stream].reset();
  }
}

bool DirectoryReader::next(SessionChunk& chunk) {
  if (!header_sent_) {
    chunk.Clear();
    *chunk.mutable_header() = header_;
    header_sent_ = true;
    return true;
  }
  std::optional<std::size_t> best;
  ChunkOrderKey best_key;
  for (std::size_t i = 0; i < pending_.size(); ++i) {
    if (!pending_[i]) continue;
    const ChunkOrderKey key = chunk_order_key(*pending_[i], header_);
    if (!best || key < best_key) {
      best = i;
      best_key = key;
    }
  }
  if (best) {
    chunk = std::move(*pending_[*best]);
    refill(*best);
    return true;
  }
  if (!end_sent_) {
    end_sent_ = true;
    if (has_entry(directory_.get(), layout::kEndJson, FileKind::kRegular)) {
      chunk.Clear();
      message_from_json(read_json_file(directory_.get(), layout::kEndJson), layout::kEndJson, *chunk.mutable_end());
      return true;
    }
  }
  return false;
}

}  // namespace posefuse::session
