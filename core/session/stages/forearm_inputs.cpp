#include "session/stages/forearm_inputs.hpp"

#include "geometry/kinect_joints.hpp"

namespace posefuse::session {

forearm::ArmFrame arm_frame_from_skeleton(const Skeleton& skeleton, forearm::Side side, std::int64_t t_us) {
  const geometry::KinectArmJoints j =
      side == forearm::Side::kLeft ? geometry::kLeftArmJoints : geometry::kRightArmJoints;
  const auto& joints = skeleton.joints;
  forearm::ArmFrame arm;
  arm.t_us = t_us;
  arm.shoulder_K = joints[j.shoulder].p_K;
  arm.elbow_K = joints[j.elbow].p_K;
  arm.wrist_K = joints[j.wrist].p_K;
  arm.shoulder_tracked = joints[j.shoulder].state == JointState::kTracked;
  arm.forearm_tracked = joints[j.elbow].state == JointState::kTracked && joints[j.wrist].state == JointState::kTracked;
  arm.sdk_elbow_K = arm.elbow_K;
  arm.sdk_wrist_K = arm.wrist_K;
  arm.sdk_elbow_seen = joints[j.elbow].state != JointState::kNotTracked;
  arm.K_from_wrist_sdk = joints[j.wrist].orientation;
  return arm;
}

geometry::DepthImageView depth_view(const cv::Mat& depth_mm) {
  if (depth_mm.empty()) return {};
  return {depth_mm.cols, depth_mm.rows, depth_mm.ptr<std::uint16_t>()};
}

geometry::GrayImageView gray_view(const cv::Mat& gray) {
  if (gray.empty()) return {};
  return {gray.cols, gray.rows, gray.ptr<std::uint8_t>()};
}

}  // namespace posefuse::session
