#pragma once
// Which BVH joint drives which SMPL joint (bvh_retarget.hpp, bvh_glitches.hpp' arm swaps).
//
// A joint map is a list of entries, one per SMPL joint, each with the BVH joint names that may
// play it. Three are built in:
//   auto     the name table of bvh_retarget.hpp: per SMPL joint several candidates, the first
//            present in the clip and not yet taken wins, optional joints may be absent (the
//            default; what every clip used before joint maps existed)
//   mocap21  the 21-joint rig of ../shared/data/mocap (MotionBuilder names), one name each
//   cmu31    CMU's 31-joint rig (LowerBack, Spine, Spine1 onto spine1..3), one name each
// and any other rig is mapped by a joint-map file (docs/simulator.md, "BVH joint maps"):
//
//   # comment; blank lines are ignored
//   smpl_joint = BvhJointName
//
// one line per SMPL joint (names of body::smpl_joint_names() except left_hand / right_hand,
// which follow the wrists), BVH names compared case-insensitively. The built-in mocap21 and
// cmu31 maps are texts in this format (bvh_joint_map_text). A file (and mocap21, cmu31) must
// map every required joint (pelvis, hips, knees, ankles, head, shoulders, elbows, wrists); the
// others may be left out (an unmapped SMPL joint keeps its rest rotation relative to its
// parent). Every name a file gives must be a joint of the clip it is used with.
//
// Errors (posefuse::Error, kInvalidArgument): a line that is not `name = name`, an unknown or
// unmappable SMPL joint, an SMPL joint or a BVH joint on two lines: field "<source>:<line>";
// a required SMPL joint without a line: field "<source>". Against a clip: a name that is not
// one of its joints: "<source>:<line>"; for the auto map, a required joint with no candidate
// present: "bvh.joints".
#include <array>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "body/smpl_model.hpp"
#include "sim/bvh.hpp"

namespace posefuse::sim {

struct BvhJointMapEntry {
  int smpl = 0;                    // body::SmplJoint
  std::vector<std::string> names;  // BVH joint names, first present and not yet taken wins
  int line = 0;                    // in the source text, 0 for a table built in code
};

struct BvhJointMap {
  std::string source;  // file name (or "mocap21", "cmu31", "auto") for errors
  // Every entry's name must be present in the clip (files, mocap21, cmu31); the auto table
  // instead skips absent candidates and only requires the required joints.
  bool strict = true;
  std::vector<BvhJointMapEntry> entries;  // resolved in this order
};

// SMPL joints every map must drive.
bool is_required_smpl_joint(int smpl);

const BvhJointMap& auto_bvh_joint_map();
// "mocap21" and "cmu31": the built-in maps' text in the file format; kInvalidArgument otherwise.
std::string_view bvh_joint_map_text(std::string_view builtin_name);

BvhJointMap parse_bvh_joint_map(std::string_view text, const std::string& source);
// kNotFound naming the path when it cannot be read; parse errors as above.
BvhJointMap load_bvh_joint_map(const std::filesystem::path& path);
// "auto", "mocap21", "cmu31", or else the path of a joint-map file.
BvhJointMap bvh_joint_map_named(const std::string& name_or_path);

struct BvhJointMatch {
  std::array<int, body::kNumJoints> bvh_joint{};  // BVH joint index per SMPL joint, -1 = none
  std::array<int, body::kNumJoints> line{};       // the map's line for it, 0 = none / built in code
};

// The map applied to a rig. With `check` false nothing is thrown: absent names are left at -1
// (for callers that only want the joints that are there, e.g. the glitch search).
BvhJointMatch match_bvh_joint_map(const BvhJointMap& map, const BvhSkeleton& skeleton, bool check = true);

// Where a map's line is named in errors: "<source>:<line>", or "bvh.joints" without a line.
std::string bvh_joint_map_field(const BvhJointMap& map, int line);

}  // namespace posefuse::sim
