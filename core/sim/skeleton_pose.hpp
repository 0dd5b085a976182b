#pragma once
// The posed SMPL skeleton alone (24 joint positions and global rotations), without skinning
// the mesh: what IMU trajectories need at 1 kHz, where evaluating every vertex would be wasted.
// Same kinematics as body::BodyEvaluator (paper 2, II-B):
//   R(j) = R(parent) * exp(omega_j),  c(j) = c(parent) + R(parent) (J(j) - J(parent)),
//   c(0) = J(0) + translation,
// with omega_j and the translation from a theta of `layout` (PoseLayout::to_smpl).
#include <array>

#include <Eigen/Core>

#include "body/body_evaluator.hpp"
#include "body/pose_parameters.hpp"
#include "body/smpl_model.hpp"
#include "body/template_generator.hpp"

namespace posefuse::sim {

struct SkeletonPose {
  Eigen::Matrix3Xd joints;                                 // 3 x 24, posed, model frame
  std::array<Eigen::Matrix3d, body::kNumJoints> rotation;  // global R(j), model frame
};

// rest_joints: 3 x 24 (e.g. BodyEvaluator::rest_joints() for the subject's betas). Throws
// posefuse::Error for wrong sizes or non-finite values.
SkeletonPose pose_skeleton(const Eigen::Matrix3Xd& rest_joints, const body::PoseLayout& layout,
                           const Eigen::Ref<const Eigen::VectorXd>& theta);

// The skeleton of a body that a BodyEvaluator has just posed.
SkeletonPose skeleton_pose_of(const body::BodyEvaluator& evaluator);

// The subject's rest joints (3 x 24) of the built-in template for a sex and betas.
Eigen::Matrix3Xd template_rest_joints(body::Sex sex, const Eigen::VectorXd& betas);

}  // namespace posefuse::sim
