#include "opensim/ground_frame.hpp"

#include <algorithm>
#include <limits>

#include "common/error.hpp"
#include "measures/joint_angles.hpp"

namespace posefuse::opensim {

std::optional<Eigen::Matrix3d> K_from_W(const session::ResultDirectory& results) {
  if (!results.calibration || !results.calibration->has_k_from_w()) return std::nullopt;
  const v1::Quaternion& q = results.calibration->k_from_w();
  const Eigen::Quaterniond K_from_W(q.w(), q.x(), q.y(), q.z());
  if (K_from_W.norm() < 0.5) return std::nullopt;  // all zero: unknown
  return K_from_W.normalized().toRotationMatrix();
}

const std::vector<session::JointRow>& marker_joints(const session::ResultDirectory& results) {
  return results.smpl_joints.empty() ? results.camera_joints : results.smpl_joints;
}

GroundFrame ground_frame(const session::ResultDirectory& results) {
  GroundFrame ground;
  Eigen::Vector3d up_K = Eigen::Vector3d::UnitY();
  if (const auto measured = K_from_W(results)) {
    up_K = *measured * Eigen::Vector3d::UnitZ();  // W is z up (docs/architecture.md, "Frames")
    ground.vertical_measured = true;
  }
  const Eigen::Vector3d front_K = -Eigen::Vector3d::UnitZ();
  if (std::abs(up_K.dot(front_K)) > 0.99)
    throw_precondition("calibration.json", "K_from_W puts the vertical along the camera's axis: no horizontal front");
  ground.G_from_K = measures::K_from_G(up_K, front_K).transpose();
  const std::vector<session::JointRow>& joints = marker_joints(results);
  if (joints.empty()) return ground;
  // Joint 0 is the pelvis (SMPL) or SpineBase (Kinect v2): the first frame's gives the
  // horizontal origin, the lowest joint centre of the session the floor.
  const auto first_root = std::find_if(joints.begin(), joints.end(), [&](const session::JointRow& row) {
    return row.joint == 0 && row.t_us == joints.front().t_us;
  });
  const Eigen::Vector3d root_G = ground.G_from_K * (first_root != joints.end() ? first_root->p_K : joints.front().p_K);
  double floor_y = std::numeric_limits<double>::infinity();
  for (const session::JointRow& row : joints) floor_y = std::min(floor_y, (ground.G_from_K * row.p_K).y());
  ground.origin_K = ground.G_from_K.transpose() * Eigen::Vector3d(root_G.x(), floor_y, root_G.z());
  return ground;
}

}  // namespace posefuse::opensim
