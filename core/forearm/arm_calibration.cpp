#include "forearm/arm_calibration.hpp"

#include <string>

#include "common/error.hpp"
#include "geometry/rotation_mean.hpp"

namespace posefuse::forearm {

ArmCalibration calibrate_arm(const CalibrationFrames& frames, const Quat& K_from_W, const CalibrationOptions& options) {
  ArmCalibration out;
  try {
    out.calibration = calibrate_forearm(frames.with_strap, K_from_W, options);
    out.has_model = true;
  } catch (const Error& strap_error) {
    out.calibration = calibrate_forearm(frames.without_strap, K_from_W, options);
    out.strap_not_seen = "the strap was seen in " + std::to_string(frames.with_strap.size()) + " of " +
                         std::to_string(frames.without_strap.size()) + " calibration frames (" + strap_error.what() +
                         ")";
  }
  const std::vector<CalibrationFrame>& used = out.has_model ? frames.with_strap : frames.without_strap;
  std::vector<Quat> held;
  for (std::size_t i = 0; i < out.calibration.frame_count; ++i) {
    held.push_back(used[out.calibration.first_frame + i].K_from_F_sdk);
  }
  out.K_from_F_held = geometry::chordal_mean(held);
  if (out.calibration.frame_count > 0) {
    out.hold_end_us = used[out.calibration.first_frame + out.calibration.frame_count - 1].t_us;
  }
  return out;
}

}  // namespace posefuse::forearm
