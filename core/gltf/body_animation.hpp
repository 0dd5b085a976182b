#pragma once
// The fitted body's motion as a skeleton animation: per fitted frame, each SMPL joint's rotation
// relative to its parent and the pelvis position, in the camera frame K.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <vector>

#include "body/smpl_model.hpp"
#include "session/result_reader.hpp"

namespace posefuse::gltf {

struct BodyPose {
  double t_s = 0;  // from the first frame
  // R_parent^T R_joint from the global rotations K_from_joint; the pelvis: K_from_pelvis.
  std::array<Eigen::Quaterniond, body::kNumJoints> local;
  Eigen::Vector3d pelvis_K = Eigen::Vector3d::Zero();
};

struct BodyAnimation {
  std::int64_t t0_us = 0;  // the first frame's camera time
  std::vector<BodyPose> frames;
  int incomplete_frames = 0;  // left out: not all 24 rotations, or no pelvis position
};

// From smpl_joint_rotations.csv and smpl_joints.csv (the pelvis at the same time). Throws
// posefuse::Error (kFailedPrecondition) "smpl_joint_rotations.csv" when the directory has no
// fitted rotations (the body fit was off), "smpl_joints.csv" when no frame has both.
BodyAnimation body_animation(const session::ResultDirectory& results);

}  // namespace posefuse::gltf
