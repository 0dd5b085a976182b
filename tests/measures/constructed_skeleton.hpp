#pragma once
// Upper-body skeletons whose ISB joint angles are known by construction (measures/joint_angles.hpp):
// the joint-angle tests and the measures stage's tests.
#include <Eigen/Geometry>
#include <numbers>

#include "measures/joint_angles.hpp"

namespace posefuse::measures::testing {

constexpr double kRad = std::numbers::pi / 180;

inline Eigen::Matrix3d Rx(double deg) {
  return Eigen::AngleAxisd(deg * kRad, Eigen::Vector3d::UnitX()).toRotationMatrix();
}
inline Eigen::Matrix3d Ry(double deg) {
  return Eigen::AngleAxisd(deg * kRad, Eigen::Vector3d::UnitY()).toRotationMatrix();
}
inline Eigen::Matrix3d Rz(double deg) {
  return Eigen::AngleAxisd(deg * kRad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

struct ArmPose {
  double plane_deg = 0, elevation_deg = 0, axial_deg = 0, elbow_deg = 0, pronation_deg = 0, girdle_deg = 0;
};

struct Built {
  PosedUpperBody body;
  Eigen::Vector3d left_thumb_K, right_thumb_K;
};

// A skeleton whose ISB angles are known by construction. Coordinates first in G (x front, y up,
// z right), with the thorax turned by Z-X-Y (flexion, tilt, axial) and the right arm by Y-X-Y;
// the left arm is the right one mirrored through the thorax's sagittal plane. Then mapped into K
// by K_from_G.
inline Built build(const Eigen::Matrix3d& K_from_G, double flexion_deg, double tilt_deg, double axial_deg,
                   const ArmPose& left, const ArmPose& right) {
  const Eigen::Matrix3d G_from_T = Rz(-flexion_deg) * Rx(tilt_deg) * Ry(axial_deg);
  Eigen::Matrix3Xd T = Eigen::Matrix3Xd::Zero(3, 24);  // in thorax coordinates
  T.col(6) = Eigen::Vector3d(0, 0, 0);
  T.col(9) = Eigen::Vector3d(0, 0.12, 0);
  T.col(12) = Eigen::Vector3d(0, 0.25, 0);
  Eigen::Vector3d thumb_T[2];
  for (int side = 0; side < 2; ++side) {
    const bool is_left = side == 0;
    const ArmPose& arm = is_left ? left : right;
    const Eigen::Vector3d mirror(1, 1, is_left ? -1 : 1);
    const Eigen::Vector3d collar(0, 0.2, 0.03);
    const Eigen::Vector3d clavicle = Rx(-arm.girdle_deg) * Eigen::Vector3d(0, 0, 0.15);  // -x tilts z up
    const Eigen::Vector3d shoulder = collar + clavicle;
    const Eigen::Matrix3d T_from_H = Ry(arm.plane_deg) * Rx(-arm.elevation_deg) * Ry(arm.axial_deg);
    const Eigen::Vector3d elbow = shoulder - T_from_H * Eigen::Vector3d(0, 0.3, 0);
    const Eigen::Vector3d fore_dir = T_from_H * (Rz(arm.elbow_deg) * Eigen::Vector3d(0, -1, 0));
    const Eigen::Vector3d wrist = elbow + 0.25 * fore_dir;
    // Neutral thumb: to the shoulder side of the flexion plane; pronation turns it about the
    // proximal forearm axis (the right thumb medially).
    const Eigen::Vector3d neutral = T_from_H * (Rz(arm.elbow_deg) * Eigen::Vector3d::UnitX());
    const Eigen::Vector3d thumb = Eigen::AngleAxisd(arm.pronation_deg * kRad, -fore_dir) * neutral;
    T.col(is_left ? 13 : 14) = collar.cwiseProduct(mirror);
    T.col(is_left ? 16 : 17) = shoulder.cwiseProduct(mirror);
    T.col(is_left ? 18 : 19) = elbow.cwiseProduct(mirror);
    T.col(is_left ? 20 : 21) = wrist.cwiseProduct(mirror);
    thumb_T[side] = thumb.cwiseProduct(mirror);
  }
  Built out;
  const Eigen::Vector3d origin_K(0.1, -0.2, 2.3);
  out.body.smpl_joints_K = (K_from_G * G_from_T * T).colwise() + origin_K;
  out.body.joint_confidence.fill(1.0);
  out.body.up_K = K_from_G * Eigen::Vector3d::UnitY();
  out.body.front_K = K_from_G * Eigen::Vector3d::UnitX();
  out.left_thumb_K = K_from_G * G_from_T * thumb_T[0];
  out.right_thumb_K = K_from_G * G_from_T * thumb_T[1];
  return out;
}

}  // namespace posefuse::measures::testing
