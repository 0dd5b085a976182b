#pragma once
// The room frame R of the simulated subject and its place in the world W.
//
// R is the body model's canonical frame (body/template_generator.hpp): metres, x to the
// subject's left at rest, y up, z to the subject's front, the floor is y = 0. Poses
// (PoseSequence, layout PoseLayout::all_joints()) and the posed mesh live in R; the camera
// session's `K_from_W` (camera_session.hpp) is, in this naming, K_from_R.
// W is the world of docs/architecture.md, "Frames" (x magnetic north, y west, z up), which IMU
// synthesis needs for gravity and the earth field. R's y is W's z; at heading 0 the subject's
// front (z_R) faces magnetic north (x_W) and its left (x_R) faces west (y_W); the heading turns R
// about the vertical, counter-clockwise seen from above (towards west).
#include "geometry/quaternion.hpp"

namespace posefuse::sim {

geometry::Quat W_from_R(double heading_rad = 0.0);

}  // namespace posefuse::sim
