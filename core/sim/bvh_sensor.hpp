#pragma once
// A sensor rigidly attached to a BVH joint: its pose trajectory on a dense grid, smooth enough
// for IMU synthesis. This drives IMUs directly from motion capture until the body model can
// carry the strap (issue 4); the mount is what the strap would be: an offset and orientation in
// the joint's frame.
#include <string>

#include "sim/bvh.hpp"
#include "sim/sensor_trajectory.hpp"

namespace posefuse::sim {

struct BvhSensorMount {
  std::string joint;                     // e.g. "RightForeArm"
  Vec3 offset_joint_m = Vec3::Zero();    // sensor origin in the joint's frame, metres
  Quat joint_from_A = Quat::Identity();  // sensor orientation in the joint's frame
};

// Per frame: W_from_A = W_from_joint * joint_from_A, p = p_joint + W_from_joint * offset. The
// frames are joined by a natural cubic spline (positions and hemisphere-aligned quaternion
// components, renormalised), which passes through every frame and is C2, then sampled every
// dt_s over the clip's duration. Motion capture noise of a few mm is amplified by double
// differentiation into accelerations of tens of m/s^2 at 60 Hz, so the frames are first
// smoothed by a zero-phase Gaussian of standard deviation smoothing_s (0 = none; at the ends
// the frames are continued by point reflection, see gaussian_smooth). kInvalidArgument naming the field for an unknown
// joint, a clip with fewer than 2 frames, or bad numbers.
SensorTrajectory bvh_sensor_trajectory(const BvhClip& clip, const BvhSensorMount& mount, double metres_per_unit,
                                       double smoothing_s = 0.0, double dt_s = 1e-3);

}  // namespace posefuse::sim
