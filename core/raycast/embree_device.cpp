#include "raycast/embree_device.hpp"

#include <mutex>
#include <string>

#include "common/error.hpp"

namespace posefuse::raycast {

std::shared_ptr<EmbreeDevice> EmbreeDevice::shared() {
  static std::mutex mutex;
  static std::weak_ptr<EmbreeDevice> current;
  std::lock_guard<std::mutex> lock(mutex);
  std::shared_ptr<EmbreeDevice> device = current.lock();
  if (!device) {
    device.reset(new EmbreeDevice());
    current = device;
  }
  return device;
}

// One build thread: sessions run one per core (docs/architecture.md, "Threads"), so Embree must
// not spawn its own pool.
EmbreeDevice::EmbreeDevice() : device_(rtcNewDevice("threads=1,set_affinity=0")) {
  if (!device_)
    throw Error(ErrorCode::kInternal, "embree.device",
                "rtcNewDevice failed: " + std::to_string(rtcGetDeviceError(nullptr)));
}

EmbreeDevice::~EmbreeDevice() { rtcReleaseDevice(device_); }

void EmbreeDevice::check(const char* what) const {
  const RTCError error = rtcGetDeviceError(device_);
  if (error != RTC_ERROR_NONE)
    throw Error(ErrorCode::kInternal, std::string("embree.") + what, "Embree error code " + std::to_string(error));
}

}  // namespace posefuse::raycast
