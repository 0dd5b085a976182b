#pragma once
// A whole-body motion of the simulated subject: one pose sequence that drives the rendered
// body, the camera skeleton and the IMUs alike.
#include <string>
#include <vector>

#include "sim/camera_session.hpp"

namespace posefuse::sim {

// A named time interval of a motion, e.g. "behind_head" (forearm likely occluded) or
// "calibration_hold" (paper 1, Fig. 3b, where the forearm model is measured).
struct MotionPhase {
  std::string name;
  double begin_s = 0.0;
  double end_s = 0.0;
};

struct BodyMotion {
  // theta of body::PoseLayout::all_joints() (translation, then a rotation vector per SMPL
  // joint) in the room frame R (room_frame.hpp), defined on [0, duration_s]. Just outside it
  // the motion continues C2-smoothly (exercises hold their rest pose; BVH motions extrapolate
  // along the end tangents), because IMU synthesis differentiates a few ms beyond the ends.
  PoseSequence poses;
  double duration_s = 0.0;
  std::vector<MotionPhase> phases;  // in time order; may be empty
  // What was wrong with the input and repaired (e.g. mocap glitches, bvh_glitches.hpp), one
  // readable line each; empty for a clean input.
  std::vector<std::string> warnings;
};

}  // namespace posefuse::sim
