#pragma once
// The calibration frames of one arm (paper 1, II-H; docs/forearm.md "Forearm model and
// calibration"): from the camera frames of the calibration window, those in which the arm shows
// the calibration pose (forearm raised, Fig. 3b) with the IMU's orientation at that time, the
// forearm orientation of the pose (the shoulder-elbow-wrist plane, its upper arm measured in
// depth where the depth showed it at enough frames, or the SDK's wrist orientation) and the
// strap where it was seen.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "forearm/forearm_model.hpp"
#include "forearm/forearm_track.hpp"

namespace posefuse::forearm {

struct CalibrationFrameOptions {
  bool pose_orientation = true;           // forearm.calibration_orientation = pose (else sdk)
  bool upper_arm_from_depth = true;       // forearm.upper_arm = depth
  std::size_t min_upper_arm_frames = 15;  // a still hold's frames (CalibrationOptions::min_still_frames)
};

struct CalibrationFrames {
  std::vector<CalibrationFrame> with_strap;     // the strap seen: the full model (II-H)
  std::vector<CalibrationFrame> without_strap;  // every frame in the pose: eq. 9 only
  // Tracked frames not in the pose (calibration_pose_check.hpp), by the first test they fail.
  std::size_t not_raised = 0;        // the forearm not raised
  std::size_t overhead = 0;          // the upper arm raised above the pose's
  std::size_t straight = 0;          // the elbow not flexed
  std::size_t upper_arm_frames = 0;  // frames whose upper arm the depth image showed
  bool depth_upper_arm = false;      // the arm plane's upper arm came from depth
};

// `frames` in time order; those after window_end_us are not used. `W_from_A_at(t_us)`: the arm
// IMU's orientation at a camera time (none outside its samples). up_K: the world's up in K.
CalibrationFrames select_calibration_frames(const std::vector<ArmFrame>& frames, std::int64_t window_end_us,
                                            const Vec3& up_K,
                                            const std::function<std::optional<Quat>(std::int64_t)>& W_from_A_at,
                                            const CalibrationFrameOptions& options);

}  // namespace posefuse::forearm
