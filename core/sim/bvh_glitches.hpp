#pragma once
// Glitches of real motion capture and their repair, before a clip drives the simulated body.
//
// Optical mocap solves fail for a frame or a few: a joint's rotation flips (often 180 degrees
// about the bone) and flips back, a joint with position channels jumps off its bone length, the
// labels of the two arms swap (the solver puts the left arm where the right one is and the
// reverse). Differentiated at 1 kHz such a frame is an impossible turn or acceleration, so the
// clip is repaired and every repair is reported by its frame range and reason:
//   arm swap      the wrists (in the frame of the joint both arms hang from) jump by more than
//                 arm_swap_min_jump arm lengths in one frame, and the arms exchanged and mirrored
//                 (x -> -x in that frame: the rig is a T-pose facing +z) are at least
//                 arm_swap_ratio times closer to the previous frame. Repaired exactly: the arm
//                 chains' local rotations (and translations) are exchanged and mirrored back, for
//                 runs of any length. Runs in order; frame 0 is taken as correctly labelled.
//   flip          a joint's local rotation steps faster than max_joint_rate_rad_s into frame a,
//                 and as fast again from some frame b to b+1 (b - a < max_glitch_frames) where
//                 the motion returns: frame b+1 is joined to frame a-1 at no more than that rate
//                 and by less than half of either jump, or the step into b+1 undoes the jump
//                 (the jump's offset, in the joint's or the parent's frame, taken off frame b
//                 lands within two steps at that rate of b+1): frames a..b are replaced by the
//                 slerp from a-1 to b+1.
//   bone length   a joint's distance to its parent (file units, from its OFFSET plus position
//                 channels) differs from its median over the clip by more than
//                 bone_length_tolerance of that median (of the rig's median bone for zero-length
//                 bones): runs of such frames, at most max_glitch_frames long, get the joint's
//                 translation interpolated linearly between the good frames around them.
// A glitch that reaches the clip's first or last frame is held at the good frame next to it (a
// flip of frame 0 shows as a jump out of it that never comes back).
// A flip that does not come back within max_glitch_frames, or a bone-length run longer than
// that, is not a glitch that interpolation can repair: kInvalidArgument naming the frame range,
// the joint and why.
#include <string>
#include <vector>

#include "sim/bvh.hpp"
#include "sim/bvh_joint_map.hpp"

namespace posefuse::sim {

struct BvhGlitchOptions {
  // Faster than any human joint's rotation relative to its parent in mocap at 60 Hz (the shared
  // clips' fastest genuine steps are listed in docs/simulator.md); > 0.
  double max_joint_rate_rad_s = 60.0;
  int max_glitch_frames = 12;          // longest run repaired by interpolation, >= 1
  double bone_length_tolerance = 0.1;  // relative, > 0
  double arm_swap_min_jump = 0.3;      // of the rest shoulder -> wrist length, > 0
  double arm_swap_ratio = 4.0;         // > 1
};

enum class BvhGlitchKind { kArmSwap, kFlip, kBoneLength };

struct BvhGlitch {
  BvhGlitchKind kind = BvhGlitchKind::kFlip;
  int first_frame = 0;  // inclusive, 0 = the first frame line
  int last_frame = 0;   // inclusive
  std::string joint;    // the BVH joint (arm swaps: the two arm roots, "LeftShoulder/RightShoulder")
  std::string reason;   // what was seen, with the numbers
  std::string repair;   // what was done about it
};

// One line: "bvh frames 377..379 (6.283..6.317 s), RightForeArm: <reason>; repaired by <how>".
std::string describe(const BvhGlitch& glitch, double frame_time_s);

struct BvhRepair {
  BvhClip clip;                     // repaired
  std::vector<BvhGlitch> glitches;  // in the order repaired: arm swaps, flips, bone lengths
};

// Throws kInvalidArgument for bad options (naming the option) and for unrepairable glitches
// (field "bvh.frames[a..b]"). The arms for the swap test are the joint map's (bvh_joint_map.hpp):
// collar (else shoulder) and wrist per side; a rig without both is not tested for swaps.
BvhRepair repair_bvh_glitches(const BvhClip& clip, const BvhGlitchOptions& options = {},
                              const BvhJointMap& joint_map = auto_bvh_joint_map());

}  // namespace posefuse::sim
