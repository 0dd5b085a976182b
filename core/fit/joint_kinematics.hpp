#pragma once
// Forward kinematics of SMPL's 24 joints only (no mesh): what the skeleton initialisation, the
// shape measurements and the arm roll need, at a fraction of BodyEvaluator's cost. Same
// equations as body/body_evaluator.hpp: R(j) = R(parent) R_loc(j),
// c(j) = c(parent) + R(parent) (J(j) - J(parent)), c(0) = J(0) + translation.
#include <Eigen/Core>
#include <array>

#include "body/pose_parameters.hpp"
#include "body/smpl_model.hpp"

namespace posefuse::fit {

// Rest joints J(beta) = J_regressor (v_template + shapedirs beta), 3 x 24. beta may be shorter
// than the model's (zero padded). Throws posefuse::Error "beta" for too many or non-finite entries.
Eigen::Matrix3Xd rest_joints(const body::SmplModel& model, const Eigen::VectorXd& beta);

// d J(beta) / d beta, (3 * 24) x B: rows 3j..3j+2 belong to joint j (J is linear in beta).
Eigen::MatrixXd rest_joint_shape_directions(const body::SmplModel& model);

struct JointPose {
  std::array<Eigen::Matrix3d, body::kNumJoints> K_from_joint;  // global rotation R(j)
  Eigen::Matrix3Xd positions_K;                                // 3 x 24
};

// Posed joints for theta of `layout` (throws as PoseLayout::to_smpl for a bad theta).
JointPose pose_joints(const Eigen::Matrix3Xd& rest_joints, const body::PoseLayout& layout,
                      const Eigen::VectorXd& theta);

}  // namespace posefuse::fit
