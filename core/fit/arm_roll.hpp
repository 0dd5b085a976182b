#pragma once
// Forearm roll and pronation/supination from the wrist IMU (paper 2, II-B): the body model has no
// roll DOF in the arms (it would twist the skin like a candy wrapper), so after the fit the roll
// of the forearm is read from the wrist IMU's orientation in the camera frame.
//
// Inputs: the fitted pose (posed SMPL joints and their global rotations, K), the IMU's K_from_A
// (paper 1, eq. 11: K_from_W * W_from_A) and the forearm calibration A_from_F (paper 1, eq. 9).
// F is the forearm frame of paper 1, the camera SDK's wrist orientation: `along_F` points from the
// elbow to the wrist (the SDK's y), `thumb_F` points to the thumb side (radial) of the forearm.
// The defaults are the simulator's camera skeleton (core/sim/camera_skeleton.cpp: y along the
// bone, x from the SMPL forearm's front axis, which is the thumb side in SMPL's palms-down T-pose).
//
// Outputs, with a = the model's forearm axis (elbow -> wrist joint):
//   roll_rad       signed angle about a from the model forearm's thumb direction (R(elbow) z: the
//                  roll-free model keeps the T-pose's thumb-forward orientation through its swing
//                  DOFs) to the IMU's thumb direction, both projected perpendicular to a. Applying
//                  it (K_from_forearm) gives the model forearm the IMU's roll.
//   pronation_rad  anatomical forearm rotation from the neutral position, in which the thumb points
//                  towards the shoulder side of the elbow's flexion plane (thumb up with the upper
//                  arm hanging and the elbow bent 90 degrees); positive = pronation (palm turning
//                  down), negative = supination. Undefined (nullopt) when the elbow is nearly
//                  straight: the flexion plane, and so the neutral position, is lost.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>

#include "fit/joint_kinematics.hpp"

namespace posefuse::fit {

enum class ArmSide { kLeft, kRight };

// Paper 1's F (x dorsal, y along the forearm): z is the thumb side on the right forearm and the
// little-finger side on the left (core/sim/forearm_strap.hpp).
inline Eigen::Vector3d thumb_axis_F(ArmSide side) {
  return side == ArmSide::kLeft ? Eigen::Vector3d(-Eigen::Vector3d::UnitZ())
                                : Eigen::Vector3d(Eigen::Vector3d::UnitZ());
}

struct ArmRollOptions {
  Eigen::Vector3d along_F = Eigen::Vector3d::UnitY();  // elbow -> wrist, in F
  Eigen::Vector3d thumb_F = Eigen::Vector3d::UnitX();  // radial (thumb) side, in F
  double min_elbow_flexion_deg = 15;                   // below: no pronation angle
};

struct ForearmRoll {
  double roll_rad = 0;
  std::optional<double> pronation_rad;
  Eigen::Matrix3d K_from_forearm = Eigen::Matrix3d::Identity();  // R(elbow) with the roll applied
  // Angle between the model's forearm axis and the IMU's along_F in K: how far the fitted forearm
  // direction and the IMU disagree (large values make the roll unreliable).
  double axis_disagreement_rad = 0;
};

// Throws posefuse::Error "K_from_A" / "A_from_F" for non-finite or far-from-unit quaternions,
// kFailedPrecondition "K_from_A" when the IMU's thumb axis lies along the fitted forearm,
// "arm_roll_options.*" for axes that are not orthonormal, "pose" when the elbow and wrist coincide.
ForearmRoll forearm_roll(const JointPose& pose, ArmSide side, const Eigen::Quaterniond& K_from_A,
                         const Eigen::Quaterniond& A_from_F, const ArmRollOptions& options = {});

}  // namespace posefuse::fit
