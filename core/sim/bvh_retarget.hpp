#pragma once
// Retargeting a BVH rig (any: the 21-joint clips, CMU's 31 joints, Poser-style names) onto the
// SMPL skeleton of the body model.
//
// Joint map: bvh_joint_map.hpp; a file or a built-in map, by default "auto", the table below
// (by name, case-insensitive; the first candidate present and not yet taken wins):
//   pelvis       Hips, hip, pelvis, Root          (required)
//   left_hip     LeftUpLeg, LeftThigh, lThigh, LeftHip  (required; right_* likewise)
//   left_knee    LeftLeg, LeftShin, lShin, LeftKnee      (required)
//   left_ankle   LeftFoot, lFoot, LeftAnkle              (required)
//   left_foot    LeftToeBase, LeftToe, lToe
//   spine1       LowerBack, Spine, abdomen
//   spine2       Spine, Spine1, chest
//   spine3       Spine1, Spine2, chest2, Chest
//   neck         Neck1, Neck, neck
//   head         Head                                     (required)
//   left_collar  LeftShoulder, LeftCollar, lCollar
//   left_shoulder LeftArm, LeftUpArm, lShldr              (required)
//   left_elbow   LeftForeArm, LeftLowArm, lForeArm        (required)
//   left_wrist   LeftHand, lHand                          (required)
//   left_hand    (none: SMPL's hand follows the wrist)
// so the 21-joint rig maps Spine -> spine1, Spine1 -> spine2 and leaves spine3 unmapped, and
// CMU's maps LowerBack, Spine, Spine1 onto spine1..3. An unmapped SMPL joint keeps its rest
// local rotation (it follows its parent), and the bone above it aims at the next mapped joint.
// A mapped joint must lie below the BVH joint of its nearest mapped SMPL ancestor.
//
// Rotations. A BVH joint's world rotation D (at zero channels every BVH joint is unrotated)
// maps its rest-pose vectors to the posed ones; SMPL's rest rotations are the identity too.
// Both rest poses are T-poses facing +z with y up, but their bones point in slightly different
// directions (legs, collar, spine). For each mapped SMPL joint j with bone direction s (rest,
// from j to the next mapped joint c below it) and the BVH's rest direction u between the
// mapped joints, the constant rest correction C_j is the smallest rotation taking s to u (for
// the pelvis: the rotation taking SMPL's (spine, hip axis) pair onto the BVH's). Then per frame
//   G_j = A_j * D_map(j) * C_j,
// where A_j is the smallest rotation that takes G_j s onto the posed BVH direction from map(j)
// to map(c) (identity when the BVH bone is one segment, which D already carries exactly;
// needed when the bone spans several BVH segments, e.g. the spine). The twist about the bone
// is D's: a BVH forearm roll channel becomes SMPL's elbow roll. A mapped joint without a
// mapped joint below (head, feet, a 21-joint wrist) uses its incoming bone for C_j and no A_j.
// SMPL local rotations are G_parent^-1 G_j.
#include <array>
#include <string>

#include <Eigen/Core>

#include "body/smpl_model.hpp"
#include "sim/bvh.hpp"
#include "sim/bvh_joint_map.hpp"

namespace posefuse::sim {

struct BvhRetargetMap {
  std::array<int, body::kNumJoints> bvh_joint{};         // BVH joint index per SMPL joint, -1 = none
  std::array<int, body::kNumJoints> aim_joint{};         // SMPL joint the bone aims at, -1 = none
  std::array<Vec3, body::kNumJoints> rest_bone{};        // s: unit rest direction towards aim_joint
  std::array<Quat, body::kNumJoints> rest_correction{};  // C_j
  std::array<bool, body::kNumJoints> aim_posed{};        // apply A_j
  double leg_length_ratio = 1.0;  // SMPL (hip -> knee -> ankle) / BVH rest leg length, per file unit
};

// Throws kInvalidArgument with field "bvh.joints" naming the SMPL joint and the names looked for
// when a required joint is missing, and when the map contradicts the BVH hierarchy or a
// required bone has zero length; with a joint-map file, a name the clip lacks and a mapped joint
// that contradicts the hierarchy are named by the file's line ("<file>:<line>",
// bvh_joint_map.hpp). rest_joints: the SMPL rest joints (3 x 24).
BvhRetargetMap make_bvh_retarget_map(const BvhSkeleton& skeleton, const Eigen::Matrix3Xd& rest_joints,
                                     const BvhJointMap& joints = auto_bvh_joint_map());

struct RetargetedFrame {
  std::array<Quat, body::kNumJoints> parent_from_joint;  // SMPL local rotations (pelvis: R_from_pelvis)
  std::array<Quat, body::kNumJoints> global;             // G_j
  Vec3 hips_R_units = Vec3::Zero();                      // BVH root joint position, in R's axes, file units
};

// One frame. The BVH world is taken as R directly (both Y up, T-pose facing +z).
RetargetedFrame retarget_frame(const BvhSkeleton& skeleton, const BvhRetargetMap& map, const BvhLocalPose& pose);

// The BVH joint positions (R axes, file units) at a frame: the directions retargeting matches.
std::vector<Vec3> bvh_joint_positions(const BvhSkeleton& skeleton, const BvhLocalPose& pose);

}  // namespace posefuse::sim
