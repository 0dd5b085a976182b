#include "session/chunk_order.hpp"

#include "common/error.hpp"

namespace posefuse::session {

ChunkOrderKey chunk_order_key(const v1::SessionChunk& chunk, const v1::SessionHeader& header) {
  switch (chunk.chunk_case()) {
    case v1::SessionChunk::kDepth: return {chunk.depth().t_us(), 0, 0};
    case v1::SessionChunk::kBodyIndex: return {chunk.body_index().t_us(), 1, 0};
    case v1::SessionChunk::kSkeleton: return {chunk.skeleton().t_us(), 2, chunk.skeleton().body_id()};
    case v1::SessionChunk::kColor: return {chunk.color().t_us(), 3, 0};
    case v1::SessionChunk::kImu: {
      const v1::ImuBatch& batch = chunk.imu();
      std::int64_t device_index = header.imu_devices_size();  // unknown devices sort last
      for (int i = 0; i < header.imu_devices_size(); ++i) {
        if (header.imu_devices(i).device_id() == batch.device_id()) device_index = i;
      }
      return {batch.t_us_size() > 0 ? batch.t_us(0) : 0, 4, device_index};
    }
    case v1::SessionChunk::kAudio: return {chunk.audio().t_us(), 5, 0};
    case v1::SessionChunk::kSyncEvent: return {chunk.sync_event().t_us(), 6, 0};
    default: break;
  }
  throw Error(ErrorCode::kInternal, "chunk", "only data chunks have a merge order");
}

}  // namespace posefuse::session
