#pragma once
// One arm's calibration from its calibration frames (paper 1, II-H; docs/forearm.md "Forearm
// model and calibration"): the full model (r, d_se, d_sw, d_ul and eq. 9) from the frames in
// which the strap was seen; where those do not hold still long enough, eq. 9 and d_ul alone from
// every frame in the pose (forearm orientation, no IMU positions).
#include <optional>
#include <string>

#include "forearm/calibration_frames.hpp"
#include "forearm/forearm_model.hpp"

namespace posefuse::forearm {

struct ArmCalibration {
  ForearmCalibration calibration;
  bool has_model = false;        // from the strap frames: r, d_se, d_sw known (eq. 10 positions)
  Quat K_from_F_held;            // the chordal mean forearm orientation of the hold's frames
  std::int64_t hold_end_us = 0;  // the last frame of the still run used
  std::string strap_not_seen;    // why the strap frames gave no model; empty when they did
};

// Throws posefuse::Error kFailedPrecondition "frames" when neither set of frames calibrates,
// naming why not (calibrate_forearm's message for every frame in the pose).
ArmCalibration calibrate_arm(const CalibrationFrames& frames, const Quat& K_from_W, const CalibrationOptions& options);

}  // namespace posefuse::forearm
