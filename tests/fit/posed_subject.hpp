#pragma once
// A subject of the built-in template posed in front of the camera (model coordinates are K),
// with the error-free camera skeleton of the simulator: the input of the skeleton-initialisation
// and personalisation tests.
#include <Eigen/Core>
#include <memory>

#include "body/pose_parameters.hpp"
#include "body/smpl_model.hpp"
#include "body/template_generator.hpp"
#include "fit/joint_kinematics.hpp"
#include "fit/tracked_skeleton.hpp"

namespace posefuse::fit::testing {

// The built-in template of either sex, built once per test binary.
const std::shared_ptr<body::SmplModel>& template_model(body::Sex sex);

// theta of `layout` for a subject facing the camera, pelvis at `depth_m`, with every named DOF
// ({name, degrees}) set; other DOFs zero.
Eigen::VectorXd facing_pose(const body::PoseLayout& layout, double depth_m,
                            std::initializer_list<std::pair<const char*, double>> degrees);

// Posed SMPL joints and the simulator's error-free 25-joint camera skeleton (all tracked).
struct PosedSubject {
  JointPose joints;
  TrackedSkeleton skeleton;
};
PosedSubject pose_subject(const body::SmplModel& model, const body::PoseLayout& layout, const Eigen::VectorXd& beta,
                          const Eigen::VectorXd& theta);

}  // namespace posefuse::fit::testing
