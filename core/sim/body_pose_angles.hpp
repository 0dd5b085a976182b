#pragma once
// Whole-body poses in anatomical angles, turned into theta of PoseLayout::all_joints() (room
// frame R, see room_frame.hpp). The scripted exercises are written in these angles.
//
// Arms use the chain of scripted_motion.hpp (ArmAngles: zero = hanging, palm to the thigh,
// thumb forward; abduction sideways, flexion forwards, humeral rotation, elbow flexion,
// supination about the forearm axis), relative to the thorax, so that a trunk tilt carries the
// arms along. SMPL's rest pose is the T-pose (arms along x, palms down, thumbs forward), which
// is ArmAngles{abduction = 90 deg}; a joint's SMPL rotation is therefore the anatomical chain
// relative to that pose:
//   shoulder: R_from_S * S_from_U(a) * S_from_U(T)^-1 * S_from_R
//   elbow:    R_from_U(T) * U_from_F(a) * R_from_U(T)^-1     (flexion and forearm roll)
// for the right arm; the left arm is the mirror image in the sagittal plane, i.e. rotation
// vectors (x, -y, -z) of the right arm's. Because the elbow carries the supination, the posed
// forearm (elbow joint) rolls, and with it the strap and the IMU.
// Scapular elevation turns the collar about the front axis (z_R; the right collar by -angle,
// the left by +angle, so positive lifts either shoulder). The trunk's lateral tilt, flexion
// and axial rotation are spread equally over spine1..spine3 (positive tilt: towards the
// subject's right, i.e. +z rotation; positive flexion: forwards, +x; rotation: +y, turning the
// chest to the left). Hands, legs and head stay at rest; the pelvis stands at the origin.
#include <Eigen/Core>

#include "sim/scripted_motion.hpp"

namespace posefuse::sim {

struct BodyPoseAngles {
  ArmAngles right_arm;
  ArmAngles left_arm;
  double right_scapular_elevation_rad = 0.0;
  double left_scapular_elevation_rad = 0.0;
  double trunk_lateral_tilt_rad = 0.0;
  double trunk_flexion_rad = 0.0;
  double trunk_rotation_rad = 0.0;
};

// Element-wise (1 - w) a + w b of every angle: exercises blend key poses with it.
BodyPoseAngles blend(const BodyPoseAngles& a, const BodyPoseAngles& b, double w);

// theta of PoseLayout::all_joints(). Throws kInvalidArgument for non-finite angles.
Eigen::VectorXd all_joints_theta(const BodyPoseAngles& angles);

// Index of joint j's first rotation component in an all_joints theta (3 + 3 j); for j = 24 the
// size of that theta (75).
inline int all_joints_rotation_index(int joint) { return 3 + 3 * joint; }

}  // namespace posefuse::sim
