#include "session/frame_assembler.hpp"

#include <algorithm>
#include <cstring>
#include <utility>

#include "common/error.hpp"
#include "common/held_bytes.hpp"
#include "session/image_codec.hpp"
#include "session/imu_batch.hpp"
#include "sync/broadcast_offsets.hpp"

namespace posefuse::session {

namespace {

// Colour frames kept for matching: a few frame periods around the waiting camera frames.
constexpr std::size_t kMaxKeptColorFrames = 16;

JointState joint_state(v1::SkeletonJoint::State state) {
  switch (state) {
    case v1::SkeletonJoint::TRACKED: return JointState::kTracked;
    case v1::SkeletonJoint::INFERRED: return JointState::kInferred;
    default: return JointState::kNotTracked;
  }
}

// The validator has checked the joint count, finite values and unit (or zero) orientations.
Skeleton skeleton_from(const v1::SkeletonFrame& frame) {
  Skeleton skeleton;
  skeleton.body_id = frame.body_id();
  for (int j = 0; j < geometry::kKinectJointCount && j < frame.joints_size(); ++j) {
    const v1::SkeletonJoint& in = frame.joints(j);
    SkeletonJoint& out = skeleton.joints[static_cast<std::size_t>(j)];
    out.p_K = {in.position_m().x(), in.position_m().y(), in.position_m().z()};
    out.state = joint_state(in.state());
    out.orientation =
        geometry::Quat(in.orientation().w(), in.orientation().x(), in.orientation().y(), in.orientation().z());
  }
  return skeleton;
}

std::string at_us(std::int64_t t_us) { return "t_us " + std::to_string(t_us); }

}  // namespace

AudioBlock audio_block(const v1::AudioChunk& chunk, unsigned channels) {
  AudioBlock audio{chunk.t_us(), {}};
  if (channels == 0) return audio;
  const std::size_t frames = chunk.pcm_s16le().size() / (2u * channels);
  audio.mono.resize(frames);
  for (std::size_t i = 0; i < frames; ++i) std::memcpy(&audio.mono[i], chunk.pcm_s16le().data() + 2 * channels * i, 2);
  return audio;
}

std::optional<ClockEvent> clock_event(const v1::SyncEvent& e) {
  ClockEvent event;
  event.device_id = e.device_id();
  event.t_us = e.t_us();
  if (e.kind() == v1::SyncEvent::BUZZER_STOP) {
    event.kind = ClockEvent::Kind::kBuzzerStop;
  } else if (e.kind() == v1::SyncEvent::BLE_BROADCAST_RECEIPT) {
    event.kind = ClockEvent::Kind::kBleReceipt;
    event.ble_sequence = sync::ble_sequence_from_payload(e.payload());
  } else {
    return std::nullopt;
  }
  return event;
}

FrameAssembler::FrameAssembler(const v1::SessionHeader& header, Options options)
    : options_(options), audio_channels_(header.audio_channels()), has_color_(header.has_color_intrinsics()) {
  if (header.color_rate_hz() > 0.0) color_tolerance_us_ = 0.5e6 / header.color_rate_hz();
  options_.max_pending_frames = std::max<std::size_t>(1, options_.max_pending_frames);
}

FrameAssembler::Pending* FrameAssembler::find_frame(std::int64_t t_us, bool (*fits)(const Pending&)) {
  Pending* best = nullptr;
  for (Pending& p : pending_) {
    if (std::llabs(p.t_us - t_us) <= kSameFrameToleranceUs && fits(p) &&
        (!best || std::llabs(p.t_us - t_us) < std::llabs(best->t_us - t_us))) {
      best = &p;
    }
  }
  return best;
}

FrameAssembler::Pending& FrameAssembler::frame_at(std::int64_t t_us, const std::string& field,
                                                  bool (*fits)(const Pending&)) {
  if (Pending* p = find_frame(t_us, fits)) return *p;
  if (last_released_us_ && t_us <= *last_released_us_) {
    throw_invalid(field + ".t_us", "is " + std::to_string(t_us) + ", but the camera frame at " +
                                       at_us(*last_released_us_) +
                                       " was already complete (camera streams interleaved out of time order)");
  }
  const auto after = std::upper_bound(pending_.begin(), pending_.end(), t_us,
                                      [](std::int64_t t, const Pending& p) { return t < p.t_us; });
  Pending& p = *pending_.insert(after, Pending{});
  p.t_us = t_us;
  p.frame.t_us = t_us;
  return p;
}

void FrameAssembler::keep_color(std::int64_t t_us, ColorImage image) {
  colors_.push_back({t_us, std::move(image), false});
  last_color_us_ = t_us;
  while (colors_.size() > kMaxKeptColorFrames) {
    if (!colors_.front().used) {
      if (!color_unmatched_++) first_color_unmatched_us_ = colors_.front().t_us;
    }
    colors_.pop_front();
  }
}

void FrameAssembler::add(const v1::SessionChunk& chunk, cv::Mat decoded, const std::string& field,
                         std::vector<SessionInput>& ready) {
  switch (chunk.chunk_case()) {
    case v1::SessionChunk::kDepth: {
      const v1::DepthFrame& d = chunk.depth();
      const std::string f = field + ".depth";
      cv::Mat depth = decoded.empty() ? decode_depth(d, f) : std::move(decoded);
      Pending& p = frame_at(d.t_us(), f, [](const Pending& q) { return !q.has_depth; });
      p.has_depth = true;
      p.t_us = d.t_us();  // the frame's time is its depth frame's
      p.frame.t_us = d.t_us();
      p.frame.depth_mm = std::move(depth);
      ++depth_frames_;
      break;
    }
    case v1::SessionChunk::kBodyIndex: {
      const v1::BodyIndexFrame& b = chunk.body_index();
      const std::string f = field + ".body_index";
      cv::Mat index = decoded.empty() ? decode_body_index(b, f) : std::move(decoded);
      ++body_index_frames_;
      Pending* p = find_frame(b.t_us(), [](const Pending& q) { return q.frame.body_index.empty(); });
      if (!p) {
        if (!body_index_unmatched_++) first_body_index_unmatched_us_ = b.t_us();
        break;
      }
      p->frame.body_index = std::move(index);
      break;
    }
    case v1::SessionChunk::kSkeleton: {
      const v1::SkeletonFrame& s = chunk.skeleton();
      Pending& p = frame_at(s.t_us(), field + ".skeleton", [](const Pending&) { return true; });
      if (p.frame.skeleton(s.body_id())) {
        throw_invalid(
            field + ".skeleton.body_id",
            "body " + std::to_string(s.body_id()) + " has a second skeleton for the camera frame at " + at_us(p.t_us));
      }
      p.frame.skeletons.push_back(skeleton_from(s));
      break;
    }
    case v1::SessionChunk::kColor: {
      keep_color(chunk.color().t_us(), ColorImage::from_frame(chunk.color(), field + ".color"));
      break;
    }
    case v1::SessionChunk::kImu: {
      ImuBlock block{chunk.imu().device_id(), samples_from_batch(chunk.imu(), field + ".imu")};
      release_ready(ready, false);
      ready.emplace_back(std::move(block));
      return;
    }
    case v1::SessionChunk::kAudio: {
      AudioBlock audio = audio_block(chunk.audio(), audio_channels_);
      release_ready(ready, false);
      ready.emplace_back(std::move(audio));
      return;
    }
    case v1::SessionChunk::kSyncEvent: {
      std::optional<ClockEvent> event = clock_event(chunk.sync_event());
      if (!event) return;  // OTHER: documented by its producer, used by no stage
      release_ready(ready, false);
      ready.emplace_back(std::move(*event));
      return;
    }
    default: return;
  }
  release_ready(ready, false);
}

void FrameAssembler::release_front(std::vector<SessionInput>& ready) {
  Pending p = std::move(pending_.front());
  pending_.pop_front();
  if (p.has_depth && p.frame.body_index.empty() && body_index_frames_ > 0) {
    if (!depth_without_body_index_++) first_depth_without_body_index_us_ = p.t_us;
  }
  if (!p.has_depth && !p.frame.body_index.empty()) {
    if (!body_index_unmatched_++) first_body_index_unmatched_us_ = p.t_us;
    p.frame.body_index = cv::Mat();
  }
  Color* nearest = nullptr;
  for (Color& c : colors_) {
    const double distance_us = static_cast<double>(std::llabs(c.t_us - p.t_us));
    // Within a colour period of a camera frame a colour frame belongs to the session's frames
    // (a faster colour stream has frames between them that no camera frame needs).
    if (distance_us <= 2.0 * color_tolerance_us_) c.used = true;
    if (distance_us <= color_tolerance_us_ &&
        (!nearest || std::llabs(c.t_us - p.t_us) < std::llabs(nearest->t_us - p.t_us))) {
      nearest = &c;
    }
  }
  if (nearest) {
    p.frame.color = nearest->image;
    p.frame.color_t_us = nearest->t_us;
  }
  last_released_us_ = p.t_us;
  ready.emplace_back(std::move(p.frame));
}

void FrameAssembler::release_ready(std::vector<SessionInput>& ready, bool all) {
  while (!pending_.empty()) {
    const Pending& front = pending_.front();
    // A later instant has begun in the depth or skeleton stream, so nothing more joins the front
    // frame's depth, body index or skeletons (each stream is in order); its colour frame may
    // still come until the colour stream passes half a colour period after it.
    const bool later_frame = pending_.size() >= 2 && pending_[1].t_us > front.t_us + kSameFrameToleranceUs;
    const bool color_passed =
        !has_color_ || (last_color_us_ && static_cast<double>(*last_color_us_ - front.t_us) >= color_tolerance_us_);
    if (!all && !(later_frame && color_passed) && pending_.size() <= options_.max_pending_frames) return;
    release_front(ready);
  }
}

namespace {
std::size_t image_bytes(const cv::Mat& image) { return image.total() * image.elemSize(); }
}  // namespace

std::size_t FrameAssembler::held_bytes() const {
  std::size_t held = posefuse::held_bytes(pending_) + posefuse::held_bytes(colors_);
  for (const Pending& p : pending_) {
    held += image_bytes(p.frame.depth_mm) + image_bytes(p.frame.body_index) + p.frame.color.held_bytes() +
            posefuse::held_bytes(p.frame.skeletons);
  }
  for (const Color& c : colors_) held += c.image.held_bytes();
  return held;
}

void FrameAssembler::finish(std::vector<SessionInput>& ready, std::vector<AssemblyWarning>& warnings) {
  release_ready(ready, true);
  for (const Color& c : colors_) {
    if (!c.used && !color_unmatched_++) first_color_unmatched_us_ = c.t_us;
  }
  colors_.clear();
  if (depth_without_body_index_ > 0) {
    warnings.push_back({"CAMERA_FRAME_INCOMPLETE", "body_index",
                        std::to_string(depth_without_body_index_) + " of " + std::to_string(depth_frames_) +
                            " depth frames had no body index frame (the first at " +
                            at_us(*first_depth_without_body_index_us_) + "): no silhouette for them"});
  }
  if (body_index_unmatched_ > 0) {
    warnings.push_back({"CAMERA_FRAME_UNMATCHED", "body_index",
                        std::to_string(body_index_unmatched_) + " body index frames matched no depth frame within " +
                            std::to_string(kSameFrameToleranceUs) + " us (the first at " +
                            at_us(*first_body_index_unmatched_us_) + "); not used"});
  }
  if (color_unmatched_ > 0) {
    warnings.push_back({"CAMERA_FRAME_UNMATCHED", "color",
                        std::to_string(color_unmatched_) + " colour frames had no camera frame within " +
                            std::to_string(static_cast<long long>(2.0 * color_tolerance_us_)) + " us (the first at " +
                            at_us(*first_color_unmatched_us_) + "); not used"});
  }
}

}  // namespace posefuse::session
