#include "sim/skeleton_pose.hpp"

#include <string>

#include "body/body_evaluator.hpp"
#include "body/template_generator.hpp"
#include "common/error.hpp"

namespace posefuse::sim {

SkeletonPose pose_skeleton(const Eigen::Matrix3Xd& rest_joints, const body::PoseLayout& layout,
                           const Eigen::Ref<const Eigen::VectorXd>& theta) {
  if (rest_joints.cols() != body::kNumJoints || !rest_joints.allFinite()) {
    throw_invalid("rest_joints", "must be 3 x 24 and finite, got 3 x " + std::to_string(rest_joints.cols()));
  }
  Eigen::Matrix3Xd rotation_vectors;
  Eigen::Vector3d translation;
  layout.to_smpl(theta, rotation_vectors, translation);  // checks size and finiteness
  SkeletonPose pose;
  pose.joints.resize(3, body::kNumJoints);
  for (int j = 0; j < body::kNumJoints; ++j) {
    const Eigen::Matrix3d local = body::rotation_from_vector(rotation_vectors.col(j));
    const int p = body::kSmplParents[static_cast<std::size_t>(j)];
    if (p < 0) {
      pose.rotation[0] = local;
      pose.joints.col(j) = rest_joints.col(j) + translation;
    } else {
      const auto parent = static_cast<std::size_t>(p);
      pose.rotation[static_cast<std::size_t>(j)] = pose.rotation[parent] * local;
      pose.joints.col(j) = pose.joints.col(p) + pose.rotation[parent] * (rest_joints.col(j) - rest_joints.col(p));
    }
  }
  return pose;
}

SkeletonPose skeleton_pose_of(const body::BodyEvaluator& evaluator) {
  SkeletonPose pose;
  pose.joints = evaluator.joints();
  for (int j = 0; j < body::kNumJoints; ++j) pose.rotation[static_cast<std::size_t>(j)] = evaluator.joint_rotation(j);
  return pose;
}

Eigen::Matrix3Xd template_rest_joints(body::Sex sex, const Eigen::VectorXd& betas) {
  body::BodyEvaluator evaluator(body::make_template(sex), body::PoseLayout::all_joints());
  evaluator.evaluate(betas, body::PoseLayout::all_joints().zero(), body::Derivatives::kNone);
  return evaluator.rest_joints();
}

}  // namespace posefuse::sim
