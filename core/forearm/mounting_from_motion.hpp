#pragma once
// The arm IMU's mounting F_from_A from natural motion, without paper 1's calibration pose
// (docs/forearm.md "Mounting from motion").
//
// The forearm axis y_F is seen by the camera in every frame (the depth-fitted elbow -> wrist
// direction) and the IMU's orientation K_from_A is known, so each frame gives y_F in A:
// A_from_K * forearm_K. Their normalised sum is the axis; its uncertainty is the residuals' RMS
// over the square root of their effective count (an AR(1) process: consecutive frames of a slow
// motion share their error).
//
// The roll about y_F is not seen directly. With the elbow flexed, the hinge plane (upper arm and
// forearm) gives the forearm's neutral frame N: y along the forearm, x = s * (upper x forearm)
// (s = +1 right, -1 left), which is F at zero pronation (the calibration pose's F,
// forearm_orientation.hpp). The IMU then shows the roll minus the pronation, phi = psi - tau,
// and tau is bounded by what a forearm can turn (+-max_twist_rad): every hinge frame narrows
// psi to [phi - max, phi + max]. A session that sweeps the whole pronation range fixes psi; one
// that never turns the forearm leaves it to the nominal mounting (the IMU's axes along F's, as
// the strap holds it) with its stated spread. Both are combined (the nominal clamped into the
// feasible interval, the RMS of the two as independent estimates).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "forearm/forearm_orientation.hpp"
#include "forearm/forearm_types.hpp"

namespace posefuse::forearm {

// One camera frame of the arm with the IMU's orientation at its time.
struct MountingFrame {
  std::int64_t t_us = 0;
  Quat K_from_A = Quat::Identity();
  Vec3 forearm_K = Vec3::Zero();    // elbow -> wrist, measured in depth (any length)
  std::optional<Vec3> upper_arm_K;  // shoulder -> elbow, where it was measured
};

struct MountingFromMotionOptions {
  // Below this elbow flexion the hinge plane is not used: a joint error e over a lever L tilts
  // its normal by about e / (L sin(flexion)), twice that of a right angle at 30 degrees.
  double min_flexion_rad = 30.0 * 3.14159265358979323846 / 180.0;
  // Pronation and supination limits each side of neutral: the widest normal human range (about
  // 80-90 degrees each); wider only makes the roll less certain, never wrong.
  double max_twist_rad = 90.0 * 3.14159265358979323846 / 180.0;
  // How far a strap worn as instructed may sit turned about the forearm (RMS).
  double nominal_roll_rms_rad = 30.0 * 3.14159265358979323846 / 180.0;
  std::size_t min_frames = 15;  // half a second at 30 Hz
  // The forearm axes seen, turned into A, scatter by the depth axis's error (a few degrees) if
  // the IMU turns with this forearm; beyond this RMS it does not, and a mounting made from them
  // could not meet the 15 degrees a confident sample must.
  double max_axis_residual_rad = 15.0 * 3.14159265358979323846 / 180.0;
};

struct MountingEstimate {
  Quat F_from_A = Quat::Identity();
  double axis_rms_rad = 0.0;  // predicted RMS angle error of y_F's direction in A
  double roll_rms_rad = 0.0;  // predicted RMS error of the roll about y_F
  std::size_t frames = 0;
  std::size_t outlier_frames = 0;  // frames left out: their axis in A beyond the robust 3-sigma rule
  std::size_t hinge_frames = 0;    // frames with the elbow flexed and the upper arm measured
  double seconds = 0.0;            // first to last frame used
  double axis_spread_rad = 0.0;    // how much the forearm turned in K: RMS angle from its mean direction
  double twist_span_rad = 0.0;     // the roll minus pronation seen over the hinge frames (noise removed)
  bool roll_from_hinge = false;    // the hinge frames bound the roll (else the nominal mounting alone)
  std::string roll_limit;          // what limits the roll, in words
};

// Frames in any order; non-finite ones and those with a zero forearm are skipped. When the axes
// in A scatter beyond max_axis_residual_rad, the frames within median + 3 x 1.4826 MAD of the
// residual angles are kept if they are a majority and scatter less (outlier_frames counts the
// rest). Returns none, with `why_not` set, when fewer than min_frames remain or no majority of
// frames agrees (the IMU does not turn with this forearm, or its orientation or the camera's
// forearm axis is wrong).
std::optional<MountingEstimate> estimate_mounting(const std::vector<MountingFrame>& frames, Side side,
                                                  const MountingFromMotionOptions& options, std::string& why_not);

// Is the IMU on the other arm? `own`: this arm's frames with this IMU's K_from_A; `other`: the
// other arm's frames with the same IMU's K_from_A. Each set's forearm axes, turned into A,
// scatter about their mean (RMS); the own set's scatter exceeds the other's by more than
// max_axis_residual_rad (in quadrature: the mismatch alone is beyond what the depth axis's error
// explains, as estimate_mounting reads that bound): the other arm explains the IMU, its own does
// not. Returns that in words, or none (also with fewer than min_frames usable frames in either
// set).
std::optional<std::string> imu_on_other_arm(const std::vector<MountingFrame>& own,
                                            const std::vector<MountingFrame>& other,
                                            const MountingFromMotionOptions& options);

// The forearm's neutral frame N (zero pronation) from the hinge plane; none when the elbow is
// flexed less than min_flexion_rad or either direction is zero.
std::optional<Quat> K_from_neutral_forearm(const Vec3& upper_arm_K, const Vec3& forearm_K, Side side,
                                           double min_flexion_rad);

}  // namespace posefuse::forearm
