#pragma once
// The order in which DirectoryReader merges its streams into one chunk stream.
//
// Data chunks are ordered by t_us, then by stream (depth, body index, skeleton, color, IMU,
// audio, sync event), then within a stream by body_id (skeleton) or the device's position in
// header.imu_devices (IMU). An IMU batch's t_us is that of its first sample. Devices have their
// own clocks, so this is an approximate time order; each stream's own order is exact.
#include <compare>
#include <cstdint>

#include "posefuse/v1/session.pb.h"

namespace posefuse::session {

struct ChunkOrderKey {
  std::int64_t t_us = 0;
  int stream_rank = 0;
  std::int64_t within_stream = 0;
  auto operator<=>(const ChunkOrderKey&) const = default;
};

// Only for data chunks (not header or end).
ChunkOrderKey chunk_order_key(const v1::SessionChunk& chunk, const v1::SessionHeader& header);

}  // namespace posefuse::session
