#include "session/session_validator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

#include "body/standing_height.hpp"
#include "common/error.hpp"
#include "imu/imu_sample.hpp"
#include "session/image_codec.hpp"
#include "session/imu_batch.hpp"

namespace posefuse::session {

namespace {

std::string number_text(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.9g", value);
  return buffer;
}

void require_finite(double value, const std::string& field) {
  if (!std::isfinite(value)) throw_invalid(field, "is " + number_text(value) + ", must be finite");
}

void require_positive(double value, const std::string& field) {
  require_finite(value, field);
  if (value <= 0) throw_invalid(field, "is " + number_text(value) + ", must be > 0");
}

// `name` is the enum's type name for the message, e.g. "DepthFrame.Encoding".
void require_enum(bool is_known, int value, const std::string& field, const char* name) {
  if (value == 0) throw_invalid(field, std::string("is unspecified (0); set a ") + name + " value");
  if (!is_known) throw_invalid(field, "unknown " + std::string(name) + " value " + std::to_string(value));
}

void require_timestamp_after(std::int64_t t_us, const std::optional<std::int64_t>& last, const std::string& field) {
  if (last && t_us <= *last) {
    throw_invalid(field, "timestamp " + std::to_string(t_us) + " us is not after the previous one in this stream (" +
                             std::to_string(*last) + " us)");
  }
}

bool is_zero(const v1::Quaternion& q) { return q.w() == 0 && q.x() == 0 && q.y() == 0 && q.z() == 0; }

void check_quaternion(const v1::Quaternion& q, const std::string& field, bool allow_zero) {
  require_finite(q.w(), field + ".w");
  require_finite(q.x(), field + ".x");
  require_finite(q.y(), field + ".y");
  require_finite(q.z(), field + ".z");
  if (allow_zero && is_zero(q)) return;
  const double norm = std::sqrt(q.w() * q.w() + q.x() * q.x() + q.y() * q.y() + q.z() * q.z());
  if (std::abs(norm - 1.0) > kUnitQuaternionTolerance) {
    throw_invalid(field, "norm is " + number_text(norm) + ", must be a unit quaternion");
  }
}

void check_vec3(const v1::Vec3& v, const std::string& field) {
  require_finite(v.x(), field + ".x");
  require_finite(v.y(), field + ".y");
  require_finite(v.z(), field + ".z");
}

void check_intrinsics(const v1::CameraIntrinsics& k, std::uint64_t max_pixels, const std::string& field) {
  if (k.width() == 0 || k.width() > kMaxImageSide) {
    throw_invalid(field + ".width",
                  "is " + std::to_string(k.width()) + ", must be 1.." + std::to_string(kMaxImageSide));
  }
  if (k.height() == 0 || k.height() > kMaxImageSide) {
    throw_invalid(field + ".height",
                  "is " + std::to_string(k.height()) + ", must be 1.." + std::to_string(kMaxImageSide));
  }
  // Frames must have this size: the bound on what one decoded frame may take.
  if (std::uint64_t{k.width()} * k.height() > max_pixels) {
    throw_invalid(field + ".width", std::to_string(k.width()) + "x" + std::to_string(k.height()) + " has more than " +
                                        std::to_string(max_pixels) + " pixels");
  }
  require_positive(k.fx(), field + ".fx");
  require_positive(k.fy(), field + ".fy");
  require_finite(k.cx(), field + ".cx");
  require_finite(k.cy(), field + ".cy");
  require_finite(k.k1(), field + ".k1");
  require_finite(k.k2(), field + ".k2");
  require_finite(k.k3(), field + ".k3");
  require_finite(k.p1(), field + ".p1");
  require_finite(k.p2(), field + ".p2");
}

void require_size(std::uint32_t width, std::uint32_t height, const v1::CameraIntrinsics& expected,
                  const std::string& field, const char* source) {
  if (width != expected.width() || height != expected.height()) {
    throw_invalid(field + (width != expected.width() ? ".width" : ".height"),
                  "frame is " + std::to_string(width) + "x" + std::to_string(height) + ", " + source + " says " +
                      std::to_string(expected.width()) + "x" + std::to_string(expected.height()));
  }
}

const v1::ImuDevice* find_device(const v1::SessionHeader& header, const std::string& device_id) {
  for (const v1::ImuDevice& device : header.imu_devices()) {
    if (device.device_id() == device_id) return &device;
  }
  return nullptr;
}

cv::Mat check_depth(const v1::DepthFrame& frame, const v1::SessionHeader& header, const std::string& field) {
  require_timestamp_in_range(frame.t_us(), field + ".t_us");
  require_enum(v1::DepthFrame::Encoding_IsValid(frame.encoding()), frame.encoding(), field + ".encoding",
               "DepthFrame.Encoding");
  require_size(frame.width(), frame.height(), header.depth_intrinsics(), field, "header.depth_intrinsics");
  return decode_depth(frame, field);
}

cv::Mat check_body_index(const v1::BodyIndexFrame& frame, const v1::SessionHeader& header, const std::string& field) {
  require_timestamp_in_range(frame.t_us(), field + ".t_us");
  require_enum(v1::BodyIndexFrame::Encoding_IsValid(frame.encoding()), frame.encoding(), field + ".encoding",
               "BodyIndexFrame.Encoding");
  require_size(frame.width(), frame.height(), header.depth_intrinsics(), field, "header.depth_intrinsics");
  const cv::Mat ids = decode_body_index(frame, field);
  for (int r = 0; r < ids.rows; ++r) {
    const std::uint8_t* row = ids.ptr<std::uint8_t>(r);
    for (int c = 0; c < ids.cols; ++c) {
      if (row[c] > kMaxBodyId && row[c] != 255) {
        throw_invalid(field + ".data", "pixel (" + std::to_string(c) + ", " + std::to_string(r) + ") is " +
                                           std::to_string(row[c]) + "; must be a body id 0..5 or 255 (background)");
      }
    }
  }
  return ids;
}

void check_skeleton(const v1::SkeletonFrame& frame, const std::string& field) {
  require_timestamp_in_range(frame.t_us(), field + ".t_us");
  if (frame.body_id() > kMaxBodyId) {
    throw_invalid(field + ".body_id", "is " + std::to_string(frame.body_id()) + ", must be 0..5");
  }
  if (frame.joints_size() != kSkeletonJointCount) {
    throw_invalid(field + ".joints",
                  "has " + std::to_string(frame.joints_size()) + " joints, expected 25 (Kinect v2 JointType order)");
  }
  for (int j = 0; j < frame.joints_size(); ++j) {
    const v1::SkeletonJoint& joint = frame.joints(j);
    const std::string joint_field = field + ".joints[" + std::to_string(j) + "]";
    check_vec3(joint.position_m(), joint_field + ".position_m");
    require_enum(v1::SkeletonJoint::State_IsValid(joint.state()), joint.state(), joint_field + ".state",
                 "SkeletonJoint.State");
    check_quaternion(joint.orientation(), joint_field + ".orientation", /*allow_zero=*/true);
  }
}

void check_color(const v1::ColorFrame& frame, const v1::SessionHeader& header, const std::string& field) {
  require_timestamp_in_range(frame.t_us(), field + ".t_us");
  if (!header.has_color_intrinsics()) {
    throw_invalid(field, "color frame, but the header has no color_intrinsics");
  }
  require_enum(v1::ColorFrame::Encoding_IsValid(frame.encoding()), frame.encoding(), field + ".encoding",
               "ColorFrame.Encoding");
  require_size(frame.width(), frame.height(), header.color_intrinsics(), field, "header.color_intrinsics");
  const ImageSize size = frame.encoding() == v1::ColorFrame::JPEG ? jpeg_size(frame.data(), field + ".data")
                                                                  : png_size(frame.data(), field + ".data");
  if (size.width != frame.width() || size.height != frame.height()) {
    throw_invalid(field + ".data", "image is " + std::to_string(size.width) + "x" + std::to_string(size.height) +
                                       ", the chunk says " + std::to_string(frame.width()) + "x" +
                                       std::to_string(frame.height()));
  }
}

void check_imu(const v1::ImuBatch& batch, const v1::SessionHeader& header, const std::string& field) {
  if (!find_device(header, batch.device_id())) {
    throw_invalid(field + ".device_id", "'" + batch.device_id() + "' is not in header.imu_devices");
  }
  for (int i = 0; i < batch.t_us_size(); ++i) {
    require_timestamp_in_range(batch.t_us(i), field + "[" + std::to_string(i) + "].t_us");
  }
  imu::validate_imu_stream(samples_from_batch(batch, field), field.c_str());
}

void check_audio(const v1::AudioChunk& audio, const v1::SessionHeader& header, const std::string& field) {
  require_timestamp_in_range(audio.t_us(), field + ".t_us");
  if (header.audio_sample_rate_hz() == 0) {
    throw_invalid(field, "audio chunk, but header.audio_sample_rate_hz is 0 (no audio stream)");
  }
  if (audio.sample_rate_hz() != header.audio_sample_rate_hz()) {
    throw_invalid(field + ".sample_rate_hz", "is " + std::to_string(audio.sample_rate_hz()) + ", header says " +
                                                 std::to_string(header.audio_sample_rate_hz()));
  }
  if (audio.channels() != header.audio_channels()) {
    throw_invalid(field + ".channels", "is " + std::to_string(audio.channels()) + ", header says " +
                                           std::to_string(header.audio_channels()));
  }
  const std::size_t frame_bytes = 2u * audio.channels();
  if (audio.pcm_s16le().empty() || audio.pcm_s16le().size() % frame_bytes != 0) {
    throw_invalid(field + ".pcm_s16le", "has " + std::to_string(audio.pcm_s16le().size()) +
                                            " bytes, must be a positive multiple of " + std::to_string(frame_bytes) +
                                            " (2 bytes x " + std::to_string(audio.channels()) + " channels)");
  }
}

void check_sync(const v1::SyncEvent& event, const v1::SessionHeader& header, const std::string& field) {
  require_timestamp_in_range(event.t_us(), field + ".t_us");
  if (event.device_id() != "camera" && !find_device(header, event.device_id())) {
    throw_invalid(field + ".device_id", "'" + event.device_id() + "' is neither \"camera\" nor in header.imu_devices");
  }
  require_enum(v1::SyncEvent::Kind_IsValid(event.kind()), event.kind(), field + ".kind", "SyncEvent.Kind");
  if (event.payload().size() > kMaxSyncPayloadBytes) {
    throw_invalid(field + ".payload", "has " + std::to_string(event.payload().size()) + " bytes, at most 4096 allowed");
  }
}

std::string kind_name(const v1::SessionChunk& chunk) {
  const auto* field = v1::SessionChunk::descriptor()->FindFieldByNumber(chunk.chunk_case());
  return field ? field->name() : "nothing";
}

}  // namespace

void require_timestamp_in_range(std::int64_t t_us, const std::string& field) {
  if (t_us < -kMaxAbsTimestampUs || t_us > kMaxAbsTimestampUs) {
    throw_invalid(field, "timestamp " + std::to_string(t_us) + " us is outside +-2^53 us (" +
                             std::to_string(kMaxAbsTimestampUs) + " us, about 285 years), the range of a device clock");
  }
}

bool is_valid_device_id(const std::string& device_id) {
  if (device_id.empty() || device_id.size() > 64 || device_id == "." || device_id == "..") {
    return false;
  }
  for (const char c : device_id) {
    const bool ok =
        (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '.' || c == '-';
    if (!ok) return false;
  }
  return true;
}

void validate_header(const v1::SessionHeader& header, const std::string& field) {
  if (header.format_version() != kFormatVersion) {
    throw_invalid(field + ".format_version", "is " + std::to_string(header.format_version()) +
                                                 ", this reader supports " + std::to_string(kFormatVersion));
  }
  if (header.subject_id().empty()) throw_invalid(field + ".subject_id", "is empty");
  if (!v1::SessionHeader::Sex_IsValid(header.sex())) {
    throw_invalid(field + ".sex", "unknown SessionHeader.Sex value " + std::to_string(header.sex()));
  }
  if (header.has_height_m()) {
    require_finite(header.height_m(), field + ".height_m");
    if (header.height_m() < body::kMinStandingHeightM || header.height_m() > body::kMaxStandingHeightM) {
      throw_invalid(field + ".height_m", "is " + number_text(header.height_m()) + " m, must be " +
                                             number_text(body::kMinStandingHeightM) + ".." +
                                             number_text(body::kMaxStandingHeightM) + " m");
    }
  }
  std::set<std::string> ids;
  for (int i = 0; i < header.imu_devices_size(); ++i) {
    const v1::ImuDevice& device = header.imu_devices(i);
    const std::string device_field = field + ".imu_devices[" + std::to_string(i) + "]";
    if (!is_valid_device_id(device.device_id())) {
      throw_invalid(device_field + ".device_id", "'" + device.device_id() + "' must match [A-Za-z0-9_.-]{1,64}");
    }
    if (!ids.insert(device.device_id()).second) {
      throw_invalid(device_field + ".device_id", "'" + device.device_id() + "' appears twice");
    }
    require_enum(v1::ImuDevice::Role_IsValid(device.role()), device.role(), device_field + ".role", "ImuDevice.Role");
    require_positive(device.nominal_rate_hz(), device_field + ".nominal_rate_hz");
  }
  if (!header.has_depth_intrinsics()) throw_invalid(field + ".depth_intrinsics", "is missing");
  check_intrinsics(header.depth_intrinsics(), kMaxDepthPixels, field + ".depth_intrinsics");
  if (header.has_color_intrinsics()) {
    check_intrinsics(header.color_intrinsics(), kMaxColorPixels, field + ".color_intrinsics");
  }
  if (header.has_color_from_depth()) {
    check_quaternion(header.color_from_depth().rotation(), field + ".color_from_depth.rotation",
                     /*allow_zero=*/false);
    check_vec3(header.color_from_depth().translation_m(), field + ".color_from_depth.translation_m");
  }
  require_positive(header.depth_rate_hz(), field + ".depth_rate_hz");
  require_finite(header.color_rate_hz(), field + ".color_rate_hz");
  if (header.color_rate_hz() < 0) {
    throw_invalid(field + ".color_rate_hz", "is " + number_text(header.color_rate_hz()) + ", must be >= 0");
  }
  if ((header.audio_sample_rate_hz() == 0) != (header.audio_channels() == 0)) {
    throw_invalid(field + ".audio_channels", "audio_sample_rate_hz " + std::to_string(header.audio_sample_rate_hz()) +
                                                 " and audio_channels " + std::to_string(header.audio_channels()) +
                                                 " must both be 0 (no audio) or both be positive");
  }
  if (header.audio_channels() > kMaxAudioChannels) {
    throw_invalid(field + ".audio_channels",
                  "is " + std::to_string(header.audio_channels()) + ", at most " + std::to_string(kMaxAudioChannels));
  }
  if (header.audio_sample_rate_hz() > kMaxAudioSampleRateHz) {
    throw_invalid(field + ".audio_sample_rate_hz", "is " + std::to_string(header.audio_sample_rate_hz()) +
                                                       ", at most " + std::to_string(kMaxAudioSampleRateHz));
  }
  for (const auto& [key, value] : header.options()) {
    if (key.empty()) throw_invalid(field + ".options", "has an empty key");
  }
}

cv::Mat validate_chunk(const v1::SessionChunk& chunk, const v1::SessionHeader& header, const std::string& field) {
  switch (chunk.chunk_case()) {
    case v1::SessionChunk::kDepth: return check_depth(chunk.depth(), header, field + ".depth");
    case v1::SessionChunk::kBodyIndex: return check_body_index(chunk.body_index(), header, field + ".body_index");
    case v1::SessionChunk::kSkeleton: check_skeleton(chunk.skeleton(), field + ".skeleton"); return {};
    case v1::SessionChunk::kColor: check_color(chunk.color(), header, field + ".color"); return {};
    case v1::SessionChunk::kImu: check_imu(chunk.imu(), header, field + ".imu"); return {};
    case v1::SessionChunk::kAudio: check_audio(chunk.audio(), header, field + ".audio"); return {};
    case v1::SessionChunk::kSyncEvent: check_sync(chunk.sync_event(), header, field + ".sync_event"); return {};
    case v1::SessionChunk::kHeader:
    case v1::SessionChunk::kEnd: throw_invalid(field, kind_name(chunk) + " is not a data chunk");
    case v1::SessionChunk::CHUNK_NOT_SET: break;
  }
  throw_invalid(field, "is empty (no chunk kind set; an unknown kind from a newer schema?)");
}

void SessionValidator::check(const v1::SessionChunk& chunk) {
  // Every chunk takes a position, also one that is rejected, so that error fields name the
  // chunk's position in the stream.
  const std::string field = "chunk[" + std::to_string(index_++) + "]";
  if (ended_) throw_invalid(field, kind_name(chunk) + " chunk after the end marker");
  if (!header_) {
    if (!chunk.has_header()) {
      throw_invalid(field, "expected the header first, got " + kind_name(chunk));
    }
    validate_header(chunk.header(), field + ".header");
    header_ = chunk.header();
  } else if (chunk.has_header()) {
    throw_invalid(field + ".header", "a second header; a session has exactly one");
  } else if (chunk.has_end()) {
    check_end(chunk.end(), field + ".end");
    ended_ = true;
  } else {
    cv::Mat decoded = validate_chunk(chunk, *header_, field);
    check_order(chunk, field);
    count(chunk);
    decoded_ = std::move(decoded);
  }
}

void SessionValidator::finish() const {
  if (!header_) throw_invalid("header", "the stream has no header (no chunks at all)");
  if (!ended_) {
    throw_invalid("end", "the stream stopped after " + std::to_string(index_) +
                             " chunks without an end marker (truncated upload or recording?)");
  }
}

void SessionValidator::check_order(const v1::SessionChunk& chunk, const std::string& field) {
  switch (chunk.chunk_case()) {
    case v1::SessionChunk::kDepth:
      require_timestamp_after(chunk.depth().t_us(), last_depth_t_us_, field + ".depth.t_us");
      last_depth_t_us_ = chunk.depth().t_us();
      note_stream_time("depth", *last_depth_t_us_, *last_depth_t_us_);
      break;
    case v1::SessionChunk::kBodyIndex:
      require_timestamp_after(chunk.body_index().t_us(), last_body_index_t_us_, field + ".body_index.t_us");
      last_body_index_t_us_ = chunk.body_index().t_us();
      note_stream_time("body_index", *last_body_index_t_us_, *last_body_index_t_us_);
      break;
    case v1::SessionChunk::kSkeleton: {
      const auto it = last_skeleton_t_us_.find(chunk.skeleton().body_id());
      std::optional<std::int64_t> last;
      if (it != last_skeleton_t_us_.end()) last = it->second;
      require_timestamp_after(chunk.skeleton().t_us(), last, field + ".skeleton.t_us");
      last_skeleton_t_us_[chunk.skeleton().body_id()] = chunk.skeleton().t_us();
      note_stream_time("skeleton/" + std::to_string(chunk.skeleton().body_id()), chunk.skeleton().t_us(),
                       chunk.skeleton().t_us());
      break;
    }
    case v1::SessionChunk::kColor:
      require_timestamp_after(chunk.color().t_us(), last_color_t_us_, field + ".color.t_us");
      last_color_t_us_ = chunk.color().t_us();
      note_stream_time("color", *last_color_t_us_, *last_color_t_us_);
      break;
    case v1::SessionChunk::kImu: {
      const v1::ImuBatch& batch = chunk.imu();
      const auto it = last_imu_t_us_.find(batch.device_id());
      std::optional<std::int64_t> last;
      if (it != last_imu_t_us_.end()) last = it->second;
      // Within the batch validate_imu_stream already checked the order.
      require_timestamp_after(batch.t_us(0), last, field + ".imu[0].t_us");
      last_imu_t_us_[batch.device_id()] = batch.t_us(batch.t_us_size() - 1);
      note_stream_time("imu/" + batch.device_id(), batch.t_us(0), batch.t_us(batch.t_us_size() - 1));
      break;
    }
    case v1::SessionChunk::kAudio:
      require_timestamp_after(chunk.audio().t_us(), last_audio_t_us_, field + ".audio.t_us");
      last_audio_t_us_ = chunk.audio().t_us();
      note_stream_time("audio", *last_audio_t_us_, *last_audio_t_us_);
      break;
    case v1::SessionChunk::kSyncEvent: {
      const v1::SyncEvent& event = chunk.sync_event();
      const auto it = last_sync_t_us_.find(event.device_id());
      if (it != last_sync_t_us_.end() && event.t_us() < it->second) {
        throw_invalid(field + ".sync_event.t_us", "timestamp " + std::to_string(event.t_us()) +
                                                      " us is before the previous event of device '" +
                                                      event.device_id() + "' (" + std::to_string(it->second) + " us)");
      }
      last_sync_t_us_[event.device_id()] = event.t_us();
      note_stream_time("sync/" + event.device_id(), event.t_us(), event.t_us());
      break;
    }
    default: break;
  }
}

void SessionValidator::note_stream_time(const std::string& stream, std::int64_t first, std::int64_t last) {
  // Both lie within +-2^53 us (require_timestamp_in_range), so the difference cannot overflow.
  const std::int64_t stream_first = first_t_us_.try_emplace(stream, first).first->second;
  stream_time_us_ = std::max(stream_time_us_, last - stream_first);
}

void SessionValidator::count(const v1::SessionChunk& chunk) {
  switch (chunk.chunk_case()) {
    case v1::SessionChunk::kDepth: counts_.set_depth_frames(counts_.depth_frames() + 1); break;
    case v1::SessionChunk::kBodyIndex: counts_.set_body_index_frames(counts_.body_index_frames() + 1); break;
    case v1::SessionChunk::kSkeleton: counts_.set_skeleton_frames(counts_.skeleton_frames() + 1); break;
    case v1::SessionChunk::kColor: counts_.set_color_frames(counts_.color_frames() + 1); break;
    case v1::SessionChunk::kImu:
      (*counts_.mutable_imu_samples())[chunk.imu().device_id()] += static_cast<std::uint64_t>(chunk.imu().t_us_size());
      break;
    case v1::SessionChunk::kAudio:
      counts_.set_audio_chunks(counts_.audio_chunks() + 1);
      counts_.set_audio_frames(counts_.audio_frames() +
                               chunk.audio().pcm_s16le().size() / (2u * chunk.audio().channels()));
      break;
    case v1::SessionChunk::kSyncEvent: counts_.set_sync_events(counts_.sync_events() + 1); break;
    default: break;
  }
}

void SessionValidator::check_end(const v1::EndOfSession& end, const std::string& field) const {
  auto compare = [&](std::uint64_t said, std::uint64_t seen, const char* name) {
    if (said != seen) {
      throw_invalid(field + "." + name, "says " + std::to_string(said) + ", the stream had " + std::to_string(seen));
    }
  };
  compare(end.depth_frames(), counts_.depth_frames(), "depth_frames");
  compare(end.body_index_frames(), counts_.body_index_frames(), "body_index_frames");
  compare(end.skeleton_frames(), counts_.skeleton_frames(), "skeleton_frames");
  compare(end.color_frames(), counts_.color_frames(), "color_frames");
  compare(end.audio_chunks(), counts_.audio_chunks(), "audio_chunks");
  compare(end.audio_frames(), counts_.audio_frames(), "audio_frames");
  compare(end.sync_events(), counts_.sync_events(), "sync_events");
  std::set<std::string> devices;
  for (const auto& [id, n] : end.imu_samples()) devices.insert(id);
  for (const auto& [id, n] : counts_.imu_samples()) devices.insert(id);
  for (const std::string& id : devices) {
    const auto said = end.imu_samples().find(id);
    const auto seen = counts_.imu_samples().find(id);
    compare(said == end.imu_samples().end() ? 0 : said->second, seen == counts_.imu_samples().end() ? 0 : seen->second,
            ("imu_samples[" + id + "]").c_str());
  }
}

}  // namespace posefuse::session
