#pragma once
// The camera skeleton's 25 joints (Kinect v2 JointType order) as the fitted body model gives
// them, so that a fit can be reported in the camera SDK's format (results.proto FrameResult.
// camera_joints) and compared joint by joint with the SDK skeleton. Same correspondence as the
// simulator's camera skeleton (core/sim/camera_skeleton.cpp): SMPL joints where one sits at the
// camera joint; Head = head joint + head_above_skull_base_m up the head; SpineShoulder = the
// collar midpoint; hand tip and thumb extrapolated from the wrist and hand joints.
#include <Eigen/Core>

#include "fit/joint_kinematics.hpp"

namespace posefuse::fit {

struct CameraJointOptions {
  double head_above_skull_base_m = 0.09;  // as SkeletonInitOptions
  double thumb_offset_m = 0.04;           // thumb beside the hand, along the hand's z axis
};

// The SMPL joint at a camera joint's position, or -1 where the camera joint is derived from
// several (Head, SpineShoulder, hand tips, thumbs).
int smpl_joint_at_camera_joint(int camera_joint);

// 3 x 25 positions in K from the posed SMPL joints.
Eigen::Matrix3Xd camera_joints_from_pose(const JointPose& pose, const CameraJointOptions& options = {});

}  // namespace posefuse::fit
