#include "posed_subject.hpp"

#include <numbers>

#include "sim/camera_skeleton.hpp"

namespace posefuse::fit::testing {

const std::shared_ptr<body::SmplModel>& template_model(body::Sex sex) {
  static const std::shared_ptr<body::SmplModel> male = body::make_template(body::Sex::kMale);
  static const std::shared_ptr<body::SmplModel> female = body::make_template(body::Sex::kFemale);
  return sex == body::Sex::kMale ? male : female;
}

Eigen::VectorXd facing_pose(const body::PoseLayout& layout, double depth_m,
                            std::initializer_list<std::pair<const char*, double>> degrees) {
  Eigen::VectorXd theta = layout.zero();
  theta[layout.index_of("translation_y")] = -0.9;
  theta[layout.index_of("translation_z")] = depth_m;
  theta[layout.index_of("pelvis_y")] = std::numbers::pi;  // face the camera
  for (const auto& [name, deg] : degrees) theta[layout.index_of(name)] += deg * std::numbers::pi / 180;
  return theta;
}

PosedSubject pose_subject(const body::SmplModel& model, const body::PoseLayout& layout, const Eigen::VectorXd& beta,
                          const Eigen::VectorXd& theta) {
  PosedSubject out;
  out.joints = pose_joints(rest_joints(model, beta), layout, theta);
  sim::SmplJointsK smpl;
  smpl.positions_K = out.joints.positions_K;
  smpl.K_from_joint = out.joints.K_from_joint;
  const Eigen::Matrix3Xd camera = sim::camera_joints_from_smpl(smpl);
  KinectSkeleton positions;
  for (int j = 0; j < kKinectJointCount; ++j) positions[j] = camera.col(j);
  out.skeleton = TrackedSkeleton::all_tracked(positions);
  return out;
}

}  // namespace posefuse::fit::testing
