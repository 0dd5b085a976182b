#pragma once
// Ground truth of one camera frame, as the papers' mocap would give it: the 24 SMPL joints and
// the 25 camera-skeleton joints (error-free) in K, and per strapped forearm the forearm frame
// K_from_F, the IMU's pose in K and whether the forearm is occluded in the camera's view.
//
// Occlusion (what hides the strap from the camera in paper 1, II-I/J): nine points on the
// forearm axis from 10 % to 90 % of the elbow -> wrist segment are tested with
// MeshScene::visible, ignoring surfaces within 6 cm before each point (the forearm's own skin,
// radius 3-4 cm on the template); anything else on the line of sight from the camera centre
// hides the point. The strap centre (F's origin) is tested the same way. `occluded`: the strap
// is hidden (paper 1's occlusion: the strap cannot be detected) or most of the forearm is.
#include <vector>

#include <Eigen/Geometry>

#include "body/body_evaluator.hpp"
#include "raycast/mesh_scene.hpp"
#include "sim/forearm_strap.hpp"

namespace posefuse::sim {

struct ForearmTruth {
  BodySide side = BodySide::kRight;
  Quat K_from_F = Quat::Identity();
  Vec3 elbow_K_m = Vec3::Zero();
  Vec3 wrist_K_m = Vec3::Zero();
  Vec3 strap_K_m = Vec3::Zero();  // F's origin
  Quat K_from_A = Quat::Identity();
  Vec3 imu_K_m = Vec3::Zero();
  double visible_fraction = 0.0;  // of the nine forearm samples
  bool strap_visible = false;
  bool occluded = false;
};

struct FrameTruth {
  Eigen::Matrix3Xd smpl_joints_K;      // 3 x 24, SMPL order
  Eigen::Matrix3Xd camera_joints_K;    // 3 x 25, Kinect v2 JointType order, before the SDK errors
  std::vector<ForearmTruth> forearms;  // one per strap, in the order given
};

// `evaluator` has just posed the body (room frame R); `scene_K` holds that posed mesh mapped by
// K_from_R (as simulate_camera_session renders it). Throws posefuse::Error for bad straps.
FrameTruth frame_truth(const body::BodyEvaluator& evaluator, const raycast::MeshScene& scene_K,
                       const Eigen::Isometry3d& K_from_R, const std::vector<ForearmStrap>& straps);

}  // namespace posefuse::sim
