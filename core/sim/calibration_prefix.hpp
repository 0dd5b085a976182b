#pragma once
// A mocap clip does not start in paper 1's calibration pose, which the forearm stage needs
// (II-H). with_calibration_prefix plays the calibration exercise up to the end of its
// calibration hold, then blends into the running clip over blend_s and plays the clip.
// with_calibration_suffix puts the pose at the end instead (a session whose calibration comes
// last: the forearm stage's mounting from motion, then the later pose and the offline solution).
#include "sim/body_motion.hpp"

namespace posefuse::sim {

// The result's theta (layout all_joints): calibration(t) for t <= t_hold_end, then per joint
// slerp(calibration(t_hold_end), clip(t - t_clip0), w) with w a smootherstep from 0 to 1 over
// blend_s (C2 at both ends, since the calibration is held still there and w', w'' vanish), then
// clip(t - t_clip0), t_clip0 = t_hold_end + blend_s. The clip is evaluated slightly before its
// start during the blend, where BodyMotion continues C2-smoothly. Phases: the calibration's, then
// the clip's shifted.
BodyMotion with_calibration_prefix(const BodyMotion& calibration, const BodyMotion& clip, double blend_s = 1.5);

// The clip, its last blend_s blended into the calibration exercise's start (its rest pose, held
// before it begins), then the whole calibration exercise: pose = slerp(clip(t), calibration(t -
// t_calib0), w) over [t_calib0 - blend_s, t_calib0], w the smootherstep, t_calib0 = the clip's
// duration. Both are evaluated only where they are C2 (the clip inside its span, the exercise
// holding its rest pose), so the result is too. Phases: the clip's, then the calibration's
// shifted. kInvalidArgument when the clip is shorter than blend_s.
BodyMotion with_calibration_suffix(const BodyMotion& clip, const BodyMotion& calibration, double blend_s = 1.5);

// End of the first "calibration_hold" phase (posefuse::Error when there is none).
double calibration_hold_end_s(const BodyMotion& motion);

}  // namespace posefuse::sim
