#include "sync/clock_map.hpp"

#include <cmath>

#include "common/error.hpp"

namespace posefuse::sync {

void ClockMap::add_direct(const std::string& device, const LinearClock& camera_from_device) {
  if (device.empty() || device == kCamera || has(device)) {
    throw_invalid("device", "'" + device + "' is empty, the camera, or already mapped");
  }
  camera_from_device_[device] = camera_from_device;
}

void ClockMap::add_via(const std::string& device, const std::string& via, const LinearClock& via_from_device) {
  if (!has(via)) throw Error(ErrorCode::kNotFound, "via", "clock '" + via + "' is not mapped");
  add_direct(device, compose(camera_from(via), via_from_device));
}

bool ClockMap::has(const std::string& device) const {
  return device == kCamera || camera_from_device_.count(device) > 0;
}

const LinearClock& ClockMap::camera_from(const std::string& device) const {
  static const LinearClock identity;
  if (device == kCamera) return identity;
  const auto it = camera_from_device_.find(device);
  if (it == camera_from_device_.end()) {
    throw Error(ErrorCode::kNotFound, "device", "clock '" + device + "' is not mapped");
  }
  return it->second;
}

double ClockMap::to_camera_us(const std::string& device, double device_us) const {
  if (!std::isfinite(device_us)) throw_invalid("device_us", "not finite");
  return camera_from(device).to_reference_us(device_us);
}

double ClockMap::sigma_us(const std::string& device, double device_us) const {
  return camera_from(device).sigma_us(device_us);
}

}  // namespace posefuse::sync
