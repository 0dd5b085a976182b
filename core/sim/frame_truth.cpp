#include "sim/frame_truth.hpp"

#include "sim/camera_skeleton.hpp"

namespace posefuse::sim {
namespace {

constexpr int kForearmSamples = 9;
// A sight line to a point on the forearm axis passes the forearm's own skin within its radius
// (3-4 cm on the template) before reaching it; only a surface farther in front hides it.
constexpr double kOwnSkinDepth_m = 0.06;

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

    Eigen::Matrix3Xd points(3, kForearmSamples + 1);
    for (int i = 0; i < kForearmSamples; ++i) {
      const double s = 0.1 + 0.8 * i / (kForearmSamples - 1);
      points.col(i) = f.elbow_K_m + s * (f.wrist_K_m - f.elbow_K_m);
    }
    points.col(kForearmSamples) = f.strap_K_m;
    const std::vector<bool> visible = scene_K.visible(points, kOwnSkinDepth_m);
    int seen = 0;
    for (int i = 0; i < kForearmSamples; ++i) seen += visible[static_cast<std::size_t>(i)] ? 1 : 0;
    f.visible_fraction = static_cast<double>(seen) / kForearmSamples;
    f.strap_visible = visible[kForearmSamples];
    f.occluded = !f.strap_visible || f.visible_fraction < 0.5;
    truth.forearms.push_back(f);
  }
  return truth;
}

}  // namespace posefuse::sim
