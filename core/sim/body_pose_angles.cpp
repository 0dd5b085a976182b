#include "sim/body_pose_angles.hpp"

#include <cmath>
#include <numbers>

#include "body/smpl_model.hpp"
#include "common/error.hpp"

namespace posefuse::sim {
namespace {

using std::numbers::pi;

// R_from_S: the scripted arm's subject frame S (x forward, y left, z up) in R (x left, y up,
// z front).
Quat R_from_S() {
  Eigen::Matrix3d m;
  m.col(0) = Vec3::UnitZ();
  m.col(1) = Vec3::UnitX();
  m.col(2) = Vec3::UnitY();
  return Quat(m);
}

ArmAngles t_pose() {
  ArmAngles a;
  a.shoulder_abduction_rad = pi / 2;
  return a;
}

ArmAngles blend(const ArmAngles& a, const ArmAngles& b, double w) {
  ArmAngles r;
  r.shoulder_abduction_rad = (1 - w) * a.shoulder_abduction_rad + w * b.shoulder_abduction_rad;
  r.shoulder_flexion_rad = (1 - w) * a.shoulder_flexion_rad + w * b.shoulder_flexion_rad;
  r.humeral_rotation_rad = (1 - w) * a.humeral_rotation_rad + w * b.humeral_rotation_rad;
  r.elbow_flexion_rad = (1 - w) * a.elbow_flexion_rad + w * b.elbow_flexion_rad;
  r.supination_rad = (1 - w) * a.supination_rad + w * b.supination_rad;
  return r;
}

void check_arm(const ArmAngles& a, const char* field) {
  for (double v : {a.shoulder_abduction_rad, a.shoulder_flexion_rad, a.humeral_rotation_rad, a.elbow_flexion_rad,
                   a.supination_rad}) {
    if (!std::isfinite(v)) throw_invalid(field, "has a non-finite angle");
  }
}

// Right-arm SMPL rotation vectors of the shoulder and the elbow.
void right_arm_rotations(const ArmAngles& a, Vec3& shoulder, Vec3& elbow) {
  const Quat R_S = R_from_S();
  const Quat S_U_rest = S_from_upper_arm(t_pose());
  const Quat R_U_rest = R_S * S_U_rest;
  shoulder = geometry::rotation_vector_from_quat(R_S * S_from_upper_arm(a) * S_U_rest.conjugate() * R_S.conjugate());
  elbow = geometry::rotation_vector_from_quat(R_U_rest * upper_arm_from_forearm(a) * R_U_rest.conjugate());
}

Vec3 mirrored(const Vec3& v) { return {v.x(), -v.y(), -v.z()}; }

void set_rotation(Eigen::VectorXd& theta, int joint, const Vec3& v) {
  theta.segment<3>(all_joints_rotation_index(joint)) = v;
}

}  // namespace

BodyPoseAngles blend(const BodyPoseAngles& a, const BodyPoseAngles& b, double w) {
  auto mix = [w](double x, double y) { return (1 - w) * x + w * y; };
  BodyPoseAngles r;
  r.right_arm = blend(a.right_arm, b.right_arm, w);
  r.left_arm = blend(a.left_arm, b.left_arm, w);
  r.right_scapular_elevation_rad = mix(a.right_scapular_elevation_rad, b.right_scapular_elevation_rad);
  r.left_scapular_elevation_rad = mix(a.left_scapular_elevation_rad, b.left_scapular_elevation_rad);
  r.trunk_lateral_tilt_rad = mix(a.trunk_lateral_tilt_rad, b.trunk_lateral_tilt_rad);
  r.trunk_flexion_rad = mix(a.trunk_flexion_rad, b.trunk_flexion_rad);
  r.trunk_rotation_rad = mix(a.trunk_rotation_rad, b.trunk_rotation_rad);
  return r;
}

Eigen::VectorXd all_joints_theta(const BodyPoseAngles& angles) {
  check_arm(angles.right_arm, "angles.right_arm");
  check_arm(angles.left_arm, "angles.left_arm");
  for (double v : {angles.right_scapular_elevation_rad, angles.left_scapular_elevation_rad,
                   angles.trunk_lateral_tilt_rad, angles.trunk_flexion_rad, angles.trunk_rotation_rad}) {
    if (!std::isfinite(v)) throw_invalid("angles", "has a non-finite trunk or scapula angle");
  }
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(all_joints_rotation_index(body::kNumJoints));
  Vec3 shoulder, elbow;
  right_arm_rotations(angles.right_arm, shoulder, elbow);
  set_rotation(theta, body::kRightShoulder, shoulder);
  set_rotation(theta, body::kRightElbow, elbow);
  right_arm_rotations(angles.left_arm, shoulder, elbow);
  set_rotation(theta, body::kLeftShoulder, mirrored(shoulder));
  set_rotation(theta, body::kLeftElbow, mirrored(elbow));
  set_rotation(theta, body::kRightCollar, Vec3(0, 0, -angles.right_scapular_elevation_rad));
  set_rotation(theta, body::kLeftCollar, Vec3(0, 0, angles.left_scapular_elevation_rad));
  const Vec3 trunk = Vec3(angles.trunk_flexion_rad, angles.trunk_rotation_rad, angles.trunk_lateral_tilt_rad) / 3.0;
  for (int j : {body::kSpine1, body::kSpine2, body::kSpine3}) set_rotation(theta, j, trunk);
  return theta;
}

}  // namespace posefuse::sim
