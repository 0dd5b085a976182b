#pragma once
// The forearm frame F and the strapped IMU on the posed body model (paper 1, II-H).
//
// F: origin at the strap centre on the forearm axis, y from the elbow to the wrist, x towards
// the back of the hand (dorsal side), z = x cross y. For the right forearm z points to the
// thumb, as in the paper (which models only the right arm); the left forearm keeps x dorsal
// and y along the bone, so its right-handed z points to the little-finger side. On the body
// model F turns with SMPL's elbow joint, whose rotation includes the forearm roll
// (pronation/supination): R_from_F = R(elbow) * R_from_F_rest, where at rest (the T-pose, palms
// down, thumbs forward) y is the elbow->wrist direction of the rest joints and x is up (y_R)
// made orthogonal to it. In F the elbow is at (0, -d_se, 0), the wrist at (0, d_sw, 0) and the
// IMU at (r, 0, 0); the IMU's orientation is F_from_A.
#include "geometry/quaternion.hpp"
#include "sim/skeleton_pose.hpp"

namespace posefuse::sim {

using geometry::Quat;
using geometry::Vec3;

enum class BodySide { kRight, kLeft };

struct ForearmStrap {
  BodySide side = BodySide::kRight;
  double strap_to_elbow_m = 0.18;  // d_se, along the forearm axis
  double strap_radius_m = 0.035;   // r: forearm axis to the IMU on the strap surface
  geometry::Quat F_from_A = geometry::Quat::Identity();
};

void validate(const ForearmStrap& strap);  // kInvalidArgument naming the field

// Everything in the room frame R (room_frame.hpp) unless named otherwise.
struct ForearmPose {
  geometry::Quat R_from_F = geometry::Quat::Identity();
  geometry::Vec3 elbow_R_m = geometry::Vec3::Zero();
  geometry::Vec3 wrist_R_m = geometry::Vec3::Zero();
  geometry::Vec3 strap_R_m = geometry::Vec3::Zero();  // F's origin
  geometry::Quat R_from_A = geometry::Quat::Identity();
  geometry::Vec3 imu_R_m = geometry::Vec3::Zero();
};

// R_from_F at rest for one side, from the rest joints (3 x 24).
geometry::Quat forearm_rest_R_from_F(const Eigen::Matrix3Xd& rest_joints, BodySide side);

// The forearm and IMU of a posed skeleton (pose_skeleton or skeleton_pose_of).
ForearmPose forearm_pose(const SkeletonPose& pose, const geometry::Quat& rest_R_from_F, const ForearmStrap& strap);

}  // namespace posefuse::sim
