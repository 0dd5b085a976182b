#pragma once
// The process's single Embree device, shared by every scene (Embree recommends one device per
// application). It lives while any scene holds it and is released with the last one.
#include <embree3/rtcore.h>

#include <memory>

namespace posefuse::raycast {

class EmbreeDevice {
 public:
  // Returns the live device, creating it on first use. Thread-safe.
  static std::shared_ptr<EmbreeDevice> shared();
  ~EmbreeDevice();
  EmbreeDevice(const EmbreeDevice&) = delete;
  EmbreeDevice& operator=(const EmbreeDevice&) = delete;

  RTCDevice handle() const { return device_; }
  // Throws posefuse::Error (kInternal) naming `what` if Embree recorded an error.
  void check(const char* what) const;

 private:
  EmbreeDevice();
  RTCDevice device_ = nullptr;
};

}  // namespace posefuse::raycast
