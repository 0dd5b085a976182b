#pragma once
// Checks a session chunk stream in order before any stage uses it.
//
// Every failure throws posefuse::Error (kInvalidArgument) whose field names the exact place,
// e.g. "chunk[7].imu[3].gyr_rad_s" or "chunk[0].header.depth_intrinsics.fx", and whose message
// gives the value and the rule, so the server can return it as INVALID_ARGUMENT unchanged.
#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include <opencv2/core.hpp>

#include "posefuse/v1/session.pb.h"

namespace posefuse::session {

// The only SessionHeader.format_version this code reads and writes.
inline constexpr std::uint32_t kFormatVersion = 1;
// A quaternion field counts as unit when | |q| - 1 | <= this.
inline constexpr double kUnitQuaternionTolerance = 1e-3;
inline constexpr int kSkeletonJointCount = 25;
inline constexpr std::uint32_t kMaxBodyId = 5;
inline constexpr std::size_t kMaxSyncPayloadBytes = 4096;
inline constexpr std::uint32_t kMaxAudioChannels = 64;
inline constexpr std::uint32_t kMaxAudioSampleRateHz = 384'000;
// Every timestamp (t_us of frames, IMU samples, audio and sync events) lies within
// +-kMaxAbsTimestampUs: 2^53 us, about 285 years either side of a clock's zero, room for any
// device clock and for Unix time in microseconds. Within it the difference of two timestamps
// cannot overflow int64 and every timestamp is exact as a double.
inline constexpr std::int64_t kMaxAbsTimestampUs = std::int64_t{1} << 53;
// Throws kInvalidArgument naming `field` for a timestamp outside that range.
void require_timestamp_in_range(std::int64_t t_us, const std::string& field);
// Device ids appear in file names (imu/<device_id>.csv): [A-Za-z0-9_.-]{1,64}, not "." or "..".
bool is_valid_device_id(const std::string& device_id);

// Checks one header on its own. `field` prefixes error field names.
void validate_header(const v1::SessionHeader& header, const std::string& field = "header");

// Checks the content of one data chunk against the header (sizes, encodings, finite values,
// enum values) but not its order in the stream. Decodes depth and body index images to check
// them and returns the decoded image (empty for other chunks); colour images are checked by
// their file header only. Header and end chunks are rejected here: they only make sense in a
// stream.
cv::Mat validate_chunk(const v1::SessionChunk& chunk, const v1::SessionHeader& header, const std::string& field);

// Checks a stream chunk by chunk: header first and exactly once, per-stream timestamp order,
// every chunk's content (validate_chunk), the end marker last with matching counts.
class SessionValidator {
 public:
  void check(const v1::SessionChunk& chunk);
  // Call after the last chunk: throws if the header or the end marker never came.
  void finish() const;
  // The depth or body index image decoded by the last accepted check() (empty otherwise), so
  // that the pipeline decodes each image once; taking it leaves it empty.
  cv::Mat take_decoded_image() { return std::move(decoded_); }

  bool has_header() const { return header_.has_value(); }
  const v1::SessionHeader& header() const { return *header_; }
  bool ended() const { return ended_; }
  // Chunks passed to check(), rejected ones included.
  std::uint64_t chunks_checked() const { return index_; }
  // Counts of what has been checked so far, as the end marker should report them.
  const v1::EndOfSession& counts() const { return counts_; }
  // How far the accepted data has advanced in time: the longest span, newest minus first
  // timestamp, of any one stream (depth, a skeleton body, an IMU device, ...). Per stream,
  // because streams run on their own clocks (an IMU's device clock may be years away from the
  // camera's), so a span across streams would measure the clocks' offset, not the recording.
  // Only accepted chunks count and each stream's timestamps only grow, so a rejected chunk (out
  // of order, outside +-2^53 us) adds nothing; at most 2^54 us. The server's minimum stream
  // rate compares it with wall time (server/stream_rate.hpp).
  std::int64_t stream_time_us() const { return stream_time_us_; }

 private:
  void check_order(const v1::SessionChunk& chunk, const std::string& field);
  void count(const v1::SessionChunk& chunk);
  void check_end(const v1::EndOfSession& end, const std::string& field) const;
  // An accepted chunk of `stream` with timestamps first..last (first <= last).
  void note_stream_time(const std::string& stream, std::int64_t first, std::int64_t last);

  std::uint64_t index_ = 0;
  std::optional<v1::SessionHeader> header_;
  cv::Mat decoded_;
  bool ended_ = false;
  v1::EndOfSession counts_;
  // Last timestamp per stream, to enforce order.
  std::optional<std::int64_t> last_depth_t_us_, last_body_index_t_us_, last_color_t_us_, last_audio_t_us_;
  std::map<std::uint32_t, std::int64_t> last_skeleton_t_us_;  // by body_id
  std::map<std::string, std::int64_t> last_imu_t_us_;         // by device_id
  std::map<std::string, std::int64_t> last_sync_t_us_;        // by device_id
  // First accepted timestamp per stream ("depth", "skeleton/1", "imu/<device_id>", ...).
  std::map<std::string, std::int64_t> first_t_us_;
  std::int64_t stream_time_us_ = 0;
};

}  // namespace posefuse::session
