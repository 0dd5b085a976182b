#include "fit/camera_joints.hpp"

#include <array>

#include "fit/tracked_skeleton.hpp"

namespace posefuse::fit {

namespace {

constexpr int kNone = -1;
constexpr std::array<int, kKinectJointCount> kSmplAt = {body::kPelvis,
                                                        body::kSpine2,
                                                        body::kNeck,
                                                        kNone,
                                                        body::kLeftShoulder,
                                                        body::kLeftElbow,
                                                        body::kLeftWrist,
                                                        body::kLeftHand,
                                                        body::kRightShoulder,
                                                        body::kRightElbow,
                                                        body::kRightWrist,
                                                        body::kRightHand,
                                                        body::kLeftHip,
                                                        body::kLeftKnee,
                                                        body::kLeftAnkle,
                                                        body::kLeftFoot,
                                                        body::kRightHip,
                                                        body::kRightKnee,
                                                        body::kRightAnkle,
                                                        body::kRightFoot,
                                                        kNone,
                                                        kNone,
                                                        kNone,
                                                        kNone,
                                                        kNone};

}  // namespace

int smpl_joint_at_camera_joint(int camera_joint) {
  return camera_joint >= 0 && camera_joint < kKinectJointCount ? kSmplAt[static_cast<size_t>(camera_joint)] : kNone;
}

Eigen::Matrix3Xd camera_joints_from_pose(const JointPose& pose, const CameraJointOptions& options) {
  const auto p = [&](int smpl_joint) -> Eigen::Vector3d { return pose.positions_K.col(smpl_joint); };
  Eigen::Matrix3Xd out(3, kKinectJointCount);
  for (int j = 0; j < kKinectJointCount; ++j) {
    if (kSmplAt[static_cast<size_t>(j)] != kNone) out.col(j) = p(kSmplAt[static_cast<size_t>(j)]);
  }
  out.col(kHead) = p(body::kHead) + options.head_above_skull_base_m * pose.K_from_joint[body::kHead].col(1);
  out.col(kSpineShoulder) = 0.5 * (p(body::kLeftCollar) + p(body::kRightCollar));
  const struct {
    int tip, thumb, wrist, hand;
  } hands[2] = {{kHandTipLeft, kThumbLeft, body::kLeftWrist, body::kLeftHand},
                {kHandTipRight, kThumbRight, body::kRightWrist, body::kRightHand}};
  for (const auto& h : hands) {
    out.col(h.tip) = 2.0 * p(h.hand) - p(h.wrist);
    out.col(h.thumb) = 0.5 * (p(h.hand) + p(h.wrist)) + options.thumb_offset_m * pose.K_from_joint[h.hand].col(2);
  }
  return out;
}

}  // namespace posefuse::fit
