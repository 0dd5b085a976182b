#include "fit/arm_roll.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "common/error.hpp"
#include "geometry/axis_angles.hpp"
#include "measures/joint_angles.hpp"

namespace posefuse::fit {
namespace {

using geometry::perpendicular;
using geometry::signed_angle;

void require_unit(const Eigen::Quaterniond& q, const char* field) {
  if (!q.coeffs().allFinite() || std::abs(q.norm() - 1.0) > 1e-6)
    throw_invalid(field, "must be a finite unit quaternion, norm " + std::to_string(q.norm()));
}

}  // namespace

ForearmRoll forearm_roll(const JointPose& pose, ArmSide side, const Eigen::Quaterniond& K_from_A,
                         const Eigen::Quaterniond& A_from_F, const ArmRollOptions& options) {
  require_unit(K_from_A, "K_from_A");
  require_unit(A_from_F, "A_from_F");
  if (!options.along_F.allFinite() || !options.thumb_F.allFinite() || std::abs(options.along_F.norm() - 1) > 1e-6 ||
      std::abs(options.thumb_F.norm() - 1) > 1e-6 || std::abs(options.along_F.dot(options.thumb_F)) > 1e-6)
    throw_invalid("arm_roll_options.thumb_F", "along_F and thumb_F must be orthogonal unit vectors");
  if (!std::isfinite(options.min_elbow_flexion_deg) || options.min_elbow_flexion_deg < 0)
    throw_invalid("arm_roll_options.min_elbow_flexion_deg", "must be finite and non-negative");
  if (pose.positions_K.cols() != body::kNumJoints || !pose.positions_K.allFinite())
    throw_invalid("pose", "needs 24 finite joints");

  const bool left = side == ArmSide::kLeft;
  const int shoulder = left ? body::kLeftShoulder : body::kRightShoulder;
  const int elbow = left ? body::kLeftElbow : body::kRightElbow;
  const int wrist = left ? body::kLeftWrist : body::kRightWrist;
  const Eigen::Vector3d forearm = pose.positions_K.col(wrist) - pose.positions_K.col(elbow);
  if (forearm.norm() < 1e-6) throw_invalid("pose", "elbow and wrist coincide");
  const Eigen::Vector3d a = forearm.normalized();

  const Eigen::Matrix3d K_from_F = (K_from_A * A_from_F).toRotationMatrix();
  const Eigen::Vector3d thumb_imu = perpendicular(K_from_F * options.thumb_F, a);
  const Eigen::Vector3d thumb_model = perpendicular(pose.K_from_joint[elbow] * Eigen::Vector3d::UnitZ(), a);
  if (thumb_imu.isZero() || thumb_model.isZero())
    throw_precondition("K_from_A",
                       "the IMU's thumb axis lies along the fitted forearm: the IMU and the fit disagree "
                       "by 90 deg about the forearm direction, no roll can be read");

  ForearmRoll out;
  out.axis_disagreement_rad = std::acos(std::clamp((K_from_F * options.along_F).dot(a), -1.0, 1.0));
  out.roll_rad = signed_angle(thumb_model, thumb_imu, a);
  out.K_from_forearm = Eigen::AngleAxisd(out.roll_rad, a).toRotationMatrix() * pose.K_from_joint[elbow];

  out.pronation_rad =
      measures::pronation_rad(pose.positions_K.col(shoulder), pose.positions_K.col(elbow), pose.positions_K.col(wrist),
                              thumb_imu, left, options.min_elbow_flexion_deg);
  return out;
}

}  // namespace posefuse::fit
