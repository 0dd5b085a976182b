#pragma once
// Every device clock mapped onto the camera clock (docs/architecture.md, "Clocks and
// timestamps"). Built from the fits: base IMU -> camera from the buzzer event(s),
// other IMUs -> base IMU from BLE broadcasts; chains them so each device maps in one step.
#include <map>
#include <string>

#include "sync/linear_clock.hpp"

namespace posefuse::sync {

class ClockMap {
 public:
  // The camera's own clock is the reference: "camera" maps with identity.
  static constexpr const char* kCamera = "camera";

  // `device` maps to the camera clock by `camera_from_device`.
  // Throws posefuse::Error kInvalidArgument "device" for an empty or duplicate name.
  void add_direct(const std::string& device, const LinearClock& camera_from_device);

  // `device` maps to the clock of the already added `via` device by `via_from_device`.
  // Throws posefuse::Error kNotFound "via" when `via` is unknown.
  void add_via(const std::string& device, const std::string& via, const LinearClock& via_from_device);

  bool has(const std::string& device) const;
  const LinearClock& camera_from(const std::string& device) const;  // kNotFound "device"
  double to_camera_us(const std::string& device, double device_us) const;
  double sigma_us(const std::string& device, double device_us) const;

 private:
  std::map<std::string, LinearClock> camera_from_device_;
};

}  // namespace posefuse::sync
