#pragma once
// Rigid forearm model (paper 1, II-H) and the IMU position from a visible strap (II-I, eq. 10).
#include <cstdint>
#include <vector>

#include "forearm/forearm_types.hpp"

namespace posefuse::forearm {

// eq. 9: ^A_F q = ^F_K q'^-1 x ^W_K q x ^A_W q, i.e. F_from_A = F_from_K' * K_from_W * W_from_A,
// with K_from_F' the camera SDK's forearm orientation in the calibration pose.
Quat F_from_A_calibration(const Quat& K_from_F_sdk, const Quat& K_from_W, const Quat& W_from_A);

// eq. 11: K_from_A = K_from_W * W_from_A and K_from_F = K_from_A * A_from_F.
Quat K_from_F_from_imu(const Quat& K_from_W, const Quat& W_from_A, const Quat& F_from_A);

// eq. 10: F's origin is the strap point projected onto the elbow-wrist segment; the IMU is at
// F_o + rot(K_from_F, [r, 0, 0]). Throws posefuse::Error kInvalidArgument "elbow_K/wrist_K" when
// elbow and wrist coincide, or a named input is not finite.
Vec3 imu_position_from_strap(const Vec3& strap_K, const Vec3& elbow_K, const Vec3& wrist_K, const Quat& K_from_F,
                             double r_m);

// One camera frame of the calibration pose (II-H): skeleton joints, the strap point seen in
// RGB/depth (II-I), the SDK forearm orientation, and the arm IMU's filter output.
struct CalibrationFrame {
  std::int64_t t_us = 0;
  Vec3 shoulder_K = Vec3::Zero();
  Vec3 elbow_K = Vec3::Zero();
  Vec3 wrist_K = Vec3::Zero();
  Vec3 strap_K = Vec3::Zero();
  Quat K_from_F_sdk = Quat::Identity();
  Quat W_from_A = Quat::Identity();
};

struct CalibrationOptions {
  // A still hold: the arm IMU's orientation within still_angle_rad of the hold's first frame, the
  // elbow within still_radius_m of its elbow and the wrist within still_radius_m of its
  // elbow -> wrist line (a depth-measured wrist moves along the forearm between frames). The IMU is the precise cue;
  // the radius is loose because the SDK's joints wander by several cm/s with the arm at rest (sim/camera_skeleton.hpp's
  // slowly turning bias; 2 cm broke 3 s holds into 14-frame runs).
  double still_angle_rad = 3.0 * 3.14159265358979323846 / 180.0;
  double still_radius_m = 0.05;
  int min_still_frames = 15;  // half a second at 30 Hz
  // A still run that cannot be a human arm holding the calibration pose is refused, however
  // long (docs/forearm.md "Refused calibrations"):
  // - its upper arm (shoulder to elbow, d_ul) outside [min_upper_arm_m, max_upper_arm_m]: the
  //   humerus lengths of a 5-year-old to the tallest adults, widened by the camera's joint error;
  // - its per-frame eq. 9 results spread (RMS) beyond max_F_from_A_spread_rad: with the IMU
  //   still, the skeleton's forearm orientations disagree, so it did not show one pose; no
  //   mounting made from it can be trusted to the 15 degrees a confident sample must meet.
  double min_upper_arm_m = 0.15;
  double max_upper_arm_m = 0.50;
  double max_F_from_A_spread_rad = 15.0 * 3.14159265358979323846 / 180.0;
  // RMS 3D error of one SDK arm joint, for d_ul's uncertainty: the middle of Kinect v2's published
  // mean arm joint errors, 50-101 mm (Wang et al. 2015, docs/simulator.md). The error is mostly a
  // slowly changing bias, so averaging the hold removes the jitter but not this.
  double camera_joint_error_m = 0.075;
};

struct ForearmCalibration {
  ForearmModel model;
  std::size_t first_frame = 0;  // the still run used
  std::size_t frame_count = 0;
  double F_from_A_spread_rad = 0.0;  // RMS angle of the per-frame eq. 9 results from their mean
  // 1-sigma error of model.d_ul_m: the shoulder's and the elbow's independent errors along the
  // upper arm, sqrt(2/3) camera_joint_error_m.
  double d_ul_uncertainty_m = 0.0;
};

// Averages r, d_se, d_sw, d_ul and eq. 9 over the longest run of still frames. Throws
// posefuse::Error: kInvalidArgument "frames[i].*" (non-finite, out-of-order), kFailedPrecondition
// "frames" when no still run reaches min_still_frames ("too short a calibration") or the run is
// refused (its upper arm length or its spread, named with the bound it breaks).
ForearmCalibration calibrate_forearm(const std::vector<CalibrationFrame>& frames, const Quat& K_from_W,
                                     const CalibrationOptions& options = {});

}  // namespace posefuse::forearm
