#pragma once
// A mocap clip does not start in paper 1's calibration pose, which the forearm stage needs
// (II-H). with_calibration_prefix plays the calibration exercise up to the end of its
// calibration hold, then blends into the running clip over blend_s and plays the clip.
#include "sim/body_motion.hpp"

namespace posefuse::sim {

// The result's theta (layout all_joints): calibration(t) for t <= t_hold_end, then per joint
// slerp(calibration(t_hold_end), clip(t - t_clip0), w) with w a smootherstep from 0 to 1 over
// blend_s (C2 at both ends, since the calibration is held still there and w', w'' vanish), then
// clip(t - t_clip0), t_clip0 = t_hold_end + blend_s. The clip is evaluated slightly before its
// start during the blend, where BodyMotion continues C2-smoothly. Phases: the calibration's, then
// the clip's shifted.
BodyMotion with_calibration_prefix(const BodyMotion& calibration, const BodyMotion& clip, double blend_s = 1.5);

// End of the first "calibration_hold" phase (posefuse::Error when there is none).
double calibration_hold_end_s(const BodyMotion& motion);

}  // namespace posefuse::sim
