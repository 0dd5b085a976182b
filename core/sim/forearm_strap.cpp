#include "sim/forearm_strap.hpp"

#include <cmath>

#include "body/smpl_model.hpp"
#include "common/error.hpp"
#include "sim/option_checks.hpp"

namespace posefuse::sim {
namespace {

int elbow_of(BodySide side) { return side == BodySide::kRight ? body::kRightElbow : body::kLeftElbow; }
int wrist_of(BodySide side) { return side == BodySide::kRight ? body::kRightWrist : body::kLeftWrist; }

}  // namespace

void validate(const ForearmStrap& strap) {
  require_non_negative(strap.strap_to_elbow_m, "strap.strap_to_elbow_m");
  require_non_negative(strap.strap_radius_m, "strap.strap_radius_m");
  if (!strap.F_from_A.coeffs().allFinite() || std::abs(strap.F_from_A.norm() - 1.0) > 1e-6) {
    throw_invalid("strap.F_from_A", "must be a unit quaternion");
  }
}

geometry::Quat forearm_rest_R_from_F(const Eigen::Matrix3Xd& rest_joints, BodySide side) {
  if (rest_joints.cols() != body::kNumJoints || !rest_joints.allFinite()) {
    throw_invalid("rest_joints", "must be 3 x 24 and finite");
  }
  const Eigen::Vector3d y = (rest_joints.col(wrist_of(side)) - rest_joints.col(elbow_of(side))).normalized();
  Eigen::Vector3d x = Eigen::Vector3d::UnitY() - Eigen::Vector3d::UnitY().dot(y) * y;
  if (!(x.norm() > 1e-6)) throw_invalid("rest_joints", "the rest forearm is vertical; no dorsal direction");
  x.normalize();
  Eigen::Matrix3d axes;
  axes << x, y, x.cross(y);
  return geometry::Quat(axes);
}

ForearmPose forearm_pose(const SkeletonPose& pose, const geometry::Quat& rest_R_from_F, const ForearmStrap& strap) {
  ForearmPose out;
  const int elbow = elbow_of(strap.side);
  out.R_from_F = (geometry::Quat(pose.rotation[static_cast<std::size_t>(elbow)]) * rest_R_from_F).normalized();
  out.elbow_R_m = pose.joints.col(elbow);
  out.wrist_R_m = pose.joints.col(wrist_of(strap.side));
  out.strap_R_m = out.elbow_R_m + out.R_from_F * geometry::Vec3(0, strap.strap_to_elbow_m, 0);
  out.imu_R_m = out.strap_R_m + out.R_from_F * geometry::Vec3(strap.strap_radius_m, 0, 0);
  out.R_from_A = (out.R_from_F * strap.F_from_A).normalized();
  return out;
}

}  // namespace posefuse::sim
