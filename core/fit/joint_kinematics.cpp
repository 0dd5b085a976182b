#include "fit/joint_kinematics.hpp"

#include <cmath>
#include <string>

#include "body/body_evaluator.hpp"
#include "common/error.hpp"

namespace posefuse::fit {

Eigen::Matrix3Xd rest_joints(const body::SmplModel& model, const Eigen::VectorXd& beta) {
  if (beta.size() > model.num_betas())
    throw_invalid("beta", "size " + std::to_string(beta.size()) + ", model has " + std::to_string(model.num_betas()) +
                              " shape directions");
  for (Eigen::Index b = 0; b < beta.size(); ++b)
    if (!std::isfinite(beta[b])) throw_invalid("beta[" + std::to_string(b) + "]", "not finite");
  Eigen::VectorXd shaped = Eigen::Map<const Eigen::VectorXd>(model.v_template.data(), 3 * model.num_vertices());
  if (beta.size() > 0) shaped.noalias() += model.shapedirs.leftCols(beta.size()) * beta;
  const Eigen::Map<const Eigen::Matrix3Xd> vertices(shaped.data(), 3, model.num_vertices());
  return vertices * model.J_regressor.transpose();
}

Eigen::MatrixXd rest_joint_shape_directions(const body::SmplModel& model) {
  Eigen::MatrixXd out(3 * body::kNumJoints, model.num_betas());
  for (int b = 0; b < model.num_betas(); ++b) {
    const Eigen::Map<const Eigen::Matrix3Xd> direction(model.shapedirs.col(b).data(), 3, model.num_vertices());
    const Eigen::Matrix3Xd joints = direction * model.J_regressor.transpose();
    out.col(b) = Eigen::Map<const Eigen::VectorXd>(joints.data(), 3 * body::kNumJoints);
  }
  return out;
}

JointPose pose_joints(const Eigen::Matrix3Xd& rest, const body::PoseLayout& layout, const Eigen::VectorXd& theta) {
  if (rest.cols() != body::kNumJoints)
    throw_invalid("rest_joints", "needs 24 columns, has " + std::to_string(rest.cols()));
  Eigen::Matrix3Xd rotation_vectors;
  Eigen::Vector3d translation;
  layout.to_smpl(theta, rotation_vectors, translation);
  JointPose pose;
  pose.positions_K.resize(3, body::kNumJoints);
  for (int j = 0; j < body::kNumJoints; ++j) {
    const Eigen::Matrix3d local = body::rotation_from_vector(rotation_vectors.col(j));
    const int p = body::kSmplParents[j];
    if (p < 0) {
      pose.K_from_joint[j] = local;
      pose.positions_K.col(j) = rest.col(j) + translation;
    } else {
      pose.K_from_joint[j] = pose.K_from_joint[p] * local;
      pose.positions_K.col(j) = pose.positions_K.col(p) + pose.K_from_joint[p] * (rest.col(j) - rest.col(p));
    }
  }
  return pose;
}

}  // namespace posefuse::fit
