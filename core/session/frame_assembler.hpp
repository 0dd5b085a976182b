#pragma once
// FrameAssembler: turns validated data chunks into the typed inputs the stages read
// (session_inputs.hpp), decoding every payload once.
//
// Camera chunks of one instant become one CameraFrame: a depth frame and the body index and
// skeletons within kSameFrameToleranceUs of it, and the colour frame nearest in time within half
// a colour period (the header's color_rate_hz; 20 ms without it). A skeleton without a depth
// frame makes a frame of its own (a session without depth still has its skeleton). A frame is
// handed on once a camera chunk after it has arrived and the colour stream has passed it, or
// when more than max_pending_frames wait (a stream that stops must not hold the rest back),
// and at the end. IMU batches, audio and clock events are handed on at once.
//
// Refusals (posefuse::Error, an ItemError for that chunk; nothing already assembled is lost):
// a camera chunk older than a frame already handed on (the streams are each in order, but
// interleaved wrongly), a second depth or body index frame for one instant, a payload that does
// not decode. What only the whole session shows is a warning at finish(): depth frames without
// a body index while the session has them, body index frames that match no depth frame, colour
// frames that no camera frame used.
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "session/session_inputs.hpp"

namespace posefuse::session {

// Depth, body index and skeleton of one instant share a time within this (clock jitter).
inline constexpr std::int64_t kSameFrameToleranceUs = 1000;

using SessionInput = std::variant<CameraFrame, ImuBlock, AudioBlock, ClockEvent>;

// An audio chunk's first channel (of `channels` interleaved).
AudioBlock audio_block(const v1::AudioChunk& chunk, unsigned channels);
// A sync event as a clock event; none for kinds no stage reads (OTHER). Throws posefuse::Error
// "sync_event.payload" for a BLE receipt whose payload is not 4 bytes.
std::optional<ClockEvent> clock_event(const v1::SyncEvent& event);

struct AssemblyWarning {
  std::string code, field, message;
};

class FrameAssembler {
 public:
  struct Options {
    std::size_t max_pending_frames = 4;
  };
  FrameAssembler(const v1::SessionHeader& header, Options options);
  explicit FrameAssembler(const v1::SessionHeader& header) : FrameAssembler(header, Options{}) {}

  // One validated data chunk; what is complete now is appended to `ready`, in stream order.
  // `decoded` is the validator's decoded depth or body index image (SessionValidator::
  // take_decoded_image), or empty to decode here. Throws posefuse::Error naming `field` for a
  // refused chunk; `ready` is then unchanged.
  void add(const v1::SessionChunk& chunk, cv::Mat decoded, const std::string& field, std::vector<SessionInput>& ready);
  // End of the stream: every waiting frame, then the session's warnings.
  void finish(std::vector<SessionInput>& ready, std::vector<AssemblyWarning>& warnings);
  // The decoded images of the frames and colour frames waiting (a few; Stage::held_bytes).
  std::size_t held_bytes() const;

 private:
  struct Pending {
    std::int64_t t_us = 0;
    bool has_depth = false;
    CameraFrame frame;
  };
  struct Color {
    std::int64_t t_us = 0;
    ColorImage image;
    bool used = false;
  };
  // The pending frame within the tolerance of t_us that `fits` accepts, or a new one at t_us
  // (in time order). Throws when t_us is older than a frame already handed on.
  Pending& frame_at(std::int64_t t_us, const std::string& field, bool (*fits)(const Pending&));
  Pending* find_frame(std::int64_t t_us, bool (*fits)(const Pending&));
  void release_ready(std::vector<SessionInput>& ready, bool all);
  void release_front(std::vector<SessionInput>& ready);
  void keep_color(std::int64_t t_us, ColorImage image);

  Options options_;
  unsigned audio_channels_ = 0;
  double color_tolerance_us_ = 20000.0;
  bool has_color_ = false;
  std::deque<Pending> pending_;  // by t_us
  std::deque<Color> colors_;     // the last few, by t_us
  std::optional<std::int64_t> last_released_us_, last_color_us_;
  std::uint64_t depth_frames_ = 0, body_index_frames_ = 0;
  std::uint64_t depth_without_body_index_ = 0, body_index_unmatched_ = 0, color_unmatched_ = 0;
  std::optional<std::int64_t> first_depth_without_body_index_us_, first_body_index_unmatched_us_,
      first_color_unmatched_us_;
};

}  // namespace posefuse::session
