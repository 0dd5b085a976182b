#pragma once
// Depth frames of the body model itself, for the fit tests and benchmark: the built-in template
// posed by a known theta and rendered with Embree (raycast::MeshScene), with a Kinect-like
// skeleton taken from the model's joints.
#include <Eigen/Core>
#include <memory>

#include "body/body_evaluator.hpp"
#include "fit/depth_frame.hpp"
#include "fit/zone_sampling.hpp"
#include "raycast/depth_camera.hpp"

namespace posefuse::fit::testing {

struct ModelFrame {
  DepthFrame frame;
  KinectSkeleton skeleton_K;  // Kinect joints at the SMPL joints (hand tips and thumbs at the hand)
  Eigen::Matrix3Xd joints_K;  // the 24 SMPL joints
};

ModelFrame render_model_frame(const std::shared_ptr<const body::SmplModel>& model, const body::PoseLayout& layout,
                              const Eigen::VectorXd& beta, const Eigen::VectorXd& theta,
                              const raycast::DepthCamera& camera);

// A pose facing the camera at `distance_m`: arms raised to the side and bent at the elbows, spine
// and head a little bent. `variant` (0, 1, 2, ...) picks different arm angles.
Eigen::VectorXd facing_pose(const body::PoseLayout& layout, double distance_m, int variant = 0);

// The unit forearm directions (elbow -> wrist) of a posed model, as the wrist IMUs would give them.
Eigen::Vector3d forearm_direction(const Eigen::Matrix3Xd& joints_K, bool left);

}  // namespace posefuse::fit::testing
