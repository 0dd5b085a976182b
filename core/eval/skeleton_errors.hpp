#pragma once
// Error statistics of one camera-skeleton joint over a session: its reported positions minus
// the truth, frame by frame. Used by bench/bench_skeleton_error to set the simulator's camera
// skeleton beside published Kinect v2 figures (docs/simulator.md, "Camera skeleton against
// published Kinect v2 figures").
//
// bias: the norm of the mean error vector (a constant offset of the joint);
// spread: the RMS distance of the errors from that mean, sqrt(mean |e - mean e|^2) (the 3D
//   spread; a per-axis SD is this over sqrt(3) for isotropic errors);
// mean_abs: the mean error norm, mean |e| (what "average joint position error" means in most
//   Kinect studies);
// off track: a frame whose error leaves the joint's own running median (per axis, over the
//   2 * half_window + 1 frames around it, clamped at the ends) by more than off_track_m. A
//   joint that jumps away for a frame or two and back is off track; a slow bias, jitter, or a
//   step that stays (an INFERRED state switching an offset on) is not.
#include <cstddef>
#include <vector>

#include "geometry/quaternion.hpp"

namespace posefuse::eval {

using geometry::Vec3;

struct JointErrorStats {
  double bias_m = 0.0;
  double spread_m = 0.0;
  double mean_abs_m = 0.0;
  std::size_t frames = 0;
  std::size_t off_track_frames = 0;
};

// Per frame, whether it is off track (see above). posefuse::Error (kInvalidArgument) for a
// non-finite error, off_track_m <= 0 or half_window < 1.
std::vector<bool> off_track_frames(const std::vector<Vec3>& errors, double off_track_m, int half_window = 2);

// The statistics above; with no errors every figure is NaN and frames 0. Same errors as
// off_track_frames.
JointErrorStats joint_error_stats(const std::vector<Vec3>& errors, double off_track_m, int half_window = 2);

}  // namespace posefuse::eval
