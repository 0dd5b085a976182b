#include "sim/frame_truth.hpp"

#include "sim/camera_skeleton.hpp"

namespace posefuse::sim {
namespace {

constexpr int kForearmSamples = 9;
constexpr double kVisibilityTolerance_m = 0.015;

// The skin point over axis point a facing the camera centre (K's origin).
Vec3 skin_towards_camera(const raycast::MeshScene& scene, const Vec3& a, const Vec3& axis) {
  Vec3 towards = -a - (-a).dot(axis) * axis;
  if (towards.norm() < 1e-9) return a;  // looking along the forearm
  towards.normalize();
  return a + scene.closest_point(a).distance * towards;
}

}  // namespace

FrameTruth frame_truth(const body::BodyEvaluator& evaluator, const raycast::MeshScene& scene_K,
                       const Eigen::Isometry3d& K_from_R, const std::vector<ForearmStrap>& straps) {
  FrameTruth truth;
  const SmplJointsK joints = smpl_joints_in_camera(evaluator, K_from_R);
  truth.smpl_joints_K = joints.positions_K;
  truth.camera_joints_K = camera_joints_from_smpl(joints);
  const SkeletonPose skeleton = skeleton_pose_of(evaluator);
  const Quat K_from_R_rotation(K_from_R.linear());
  for (const ForearmStrap& strap : straps) {
    validate(strap);
    const ForearmPose pose = forearm_pose(skeleton, forearm_rest_R_from_F(evaluator.rest_joints(), strap.side), strap);
    ForearmTruth f;
    f.side = strap.side;
    f.K_from_F = (K_from_R_rotation * pose.R_from_F).normalized();
    f.elbow_K_m = K_from_R * pose.elbow_R_m;
    f.wrist_K_m = K_from_R * pose.wrist_R_m;
    f.strap_K_m = K_from_R * pose.strap_R_m;
    f.K_from_A = (K_from_R_rotation * pose.R_from_A).normalized();
    f.imu_K_m = K_from_R * pose.imu_R_m;

    const Vec3 axis = (f.wrist_K_m - f.elbow_K_m).normalized();
    Eigen::Matrix3Xd points(3, kForearmSamples + 1);
    for (int i = 0; i < kForearmSamples; ++i) {
      const double s = 0.1 + 0.8 * i / (kForearmSamples - 1);
      points.col(i) = skin_towards_camera(scene_K, f.elbow_K_m + s * (f.wrist_K_m - f.elbow_K_m), axis);
    }
    points.col(kForearmSamples) = skin_towards_camera(scene_K, f.strap_K_m, axis);
    const std::vector<bool> visible = scene_K.visible(points, kVisibilityTolerance_m);
    int seen = 0;
    for (int i = 0; i < kForearmSamples; ++i) seen += visible[static_cast<std::size_t>(i)] ? 1 : 0;
    f.visible_fraction = static_cast<double>(seen) / kForearmSamples;
    f.strap_visible = visible[kForearmSamples];
    f.occluded = f.visible_fraction < 0.5;
    truth.forearms.push_back(f);
  }
  return truth;
}

}  // namespace posefuse::sim
