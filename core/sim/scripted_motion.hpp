#pragma once
// Scripted forearm motions as IMU pose trajectories, before the body model exists.
//
// A right arm as a kinematic chain: a fixed shoulder, a 3-DOF shoulder (abduction, flexion,
// humeral rotation), elbow flexion, forearm supination, and the IMU strapped to the forearm
// (paper 1, II-H: strap at distance d_se from the elbow, IMU on the strap surface at radius r on
// the dorsal side, orientation F_from_A).
//
// Frames: S the subject (x forward, y left, z up), W_from_S a turn by heading about z with the
// shoulder at shoulder_p_W_m. F the forearm (paper 1, II-H): y elbow -> wrist, x towards the
// back of the hand, z towards the thumb. The upper-arm frame U has the same axes for the upper
// arm (y shoulder -> elbow). With all angles zero the arm hangs, palm facing the thigh, thumb
// forward: y_F = -z_S, z_F = x_S, x_F = -y_S. Then
//   S_from_U = R(x_S, -abduction) * R(-y_S, flexion) * S_from_U0 * R(y_U, humeral_rotation)
//   U_from_F = R(x, elbow_flexion) * R(y, supination)
// Positive abduction lifts the arm sideways (to the right), positive flexion forwards, positive
// elbow flexion brings the hand forwards/up, positive supination (about y_F) turns the thumb
// outwards (laterally), i.e. supination for a right arm.
#include <functional>

#include "sim/sensor_trajectory.hpp"

namespace posefuse::sim {

struct ArmGeometry {
  Vec3 shoulder_p_W_m = Vec3(0.0, -0.18, 1.40);  // right shoulder of a subject at the origin
  double heading_rad = 0.0;                      // the subject faces W's x turned by this about z
  double upper_arm_m = 0.30;                     // shoulder to elbow
  double strap_to_elbow_m = 0.20;                // d_se
  double strap_radius_m = 0.035;                 // r: forearm axis to the strap surface
  Quat F_from_A = Quat::Identity();              // IMU orientation on the forearm
};

struct ArmAngles {
  double shoulder_abduction_rad = 0.0;
  double shoulder_flexion_rad = 0.0;
  double humeral_rotation_rad = 0.0;
  double elbow_flexion_rad = 0.0;
  double supination_rad = 0.0;
};

struct ArmPose {
  Quat W_from_F = Quat::Identity();
  Vec3 elbow_p_W_m = Vec3::Zero();
  Vec3 strap_p_W_m = Vec3::Zero();  // strap centre on the forearm axis (F's origin)
  Quat W_from_A = Quat::Identity();
  Vec3 imu_p_W_m = Vec3::Zero();  // strap centre + r along x_F
};

ArmPose arm_pose(const ArmGeometry& geometry, const ArmAngles& angles);

// The two rotations of the chain above: S_from_U (upper arm in the subject frame) and U_from_F
// (forearm in the upper arm's frame).
Quat S_from_upper_arm(const ArmAngles& angles);
Quat upper_arm_from_forearm(const ArmAngles& angles);

// 0 -> 1 for x from 0 to 1 (clamped outside) with zero first and second derivatives at both
// ends: 6x^5 - 15x^4 + 10x^3. Ramps built from it are C2.
double smootherstep(double x);

// A motion: joint angles as a function of time on [0, duration_s] (held constant outside).
struct ScriptedMotion {
  std::function<ArmAngles(double t_s)> angles;
  double duration_s = 0.0;
};

// The IMU's pose trajectory on a grid of step dt_s, covering [0, duration] plus the two grid
// points each side that SensorKinematics needs, so that its valid range is [0, duration].
SensorTrajectory imu_trajectory(const ArmGeometry& geometry, const ScriptedMotion& motion, double dt_s = 1e-3);

// Forearm rolling: elbow flexed, forearm pointing forwards, thumb up; pronation/supination
// amplitude_rad either side of neutral, `repetitions` full cycles of period_s, faded in and out
// over half a cycle (C2-smooth, so rates and accelerations are continuous), still for hold_s
// before and after.
struct ForearmRollingOptions {
  double amplitude_rad = 60.0 * static_cast<double>(EIGEN_PI) / 180.0;
  double period_s = 2.0;
  int repetitions = 5;
  double hold_s = 1.0;
  double elbow_flexion_rad = 90.0 * static_cast<double>(EIGEN_PI) / 180.0;
};
ScriptedMotion forearm_rolling(const ForearmRollingOptions& options);

// Arm raising with a straight elbow, sideways (abduction) or forwards (flexion), from hanging
// to peak_rad and back, `repetitions` times; each raise and lower is a C2-smooth ramp.
struct ArmRaisingOptions {
  enum class Plane { kFrontal, kSagittal };
  Plane plane = Plane::kFrontal;
  double peak_rad = 150.0 * static_cast<double>(EIGEN_PI) / 180.0;
  double raise_s = 2.0;
  double lower_s = 2.0;
  double pause_top_s = 0.5;
  double pause_bottom_s = 0.5;  // between repetitions
  int repetitions = 3;
  double hold_s = 1.0;  // still before and after
};
ScriptedMotion arm_raising(const ArmRaisingOptions& options);

// The calibration pose of paper 1 (Fig. 3b): upper arm sideways, horizontal; forearm vertical,
// hand at head level, palm facing forwards (the camera); both in the coronal plane. Held for
// duration_s with an optional slow postural sway (sway_rad at every joint, sway_hz).
struct CalibrationHoldOptions {
  double duration_s = 5.0;
  double sway_rad = 0.0;
  double sway_hz = 0.25;
};
ScriptedMotion calibration_hold(const CalibrationHoldOptions& options);
ArmAngles calibration_pose_angles();

}  // namespace posefuse::sim
