#pragma once
// Gap recovery beyond paper 1: one least-squares trajectory over the gap and the 500 ms either
// side, solved for the IMU position at every arm sample.
//
// Paper 1 (IV-B) reports its recovery turning back too early when the entry velocity v0 from
// the 500 ms line fit is too small: a line through a track that accelerates into the gap gives
// the window's mean velocity, not the velocity at its end. Here nothing is reduced to a line:
// the raw visible positions on both sides and the accelerations everywhere constrain the same
// trajectory, so the boundary velocity is whatever the positions *and* the accelerations imply.
//
// Unknowns: p_i at the arm sample times in [t_start - W, t_end + W], a constant accelerometer
// bias b_A, and an acceleration error in K that is linear over the window, e0 + tau e1 with
// tau in [-1, 1]: gravity leaking through a slowly wandering attitude error, which is neither
// white nor constant in A. Residuals (each divided by its sigma):
//   acceleration  second difference of p at i - (rot(K_from_A_i, f_i - b_A) - g_K - e0 - tau_i e1)
//                 (eq. 12 with the error terms)
//   position      visible track sample z_j - p(t_j) (linear between the two nearest p_i)
//   sphere        |p_i - C_i| - d_ul, C_i from eq. 13 (soft: the shoulder is itself measured)
//   elbow anchor  p(t_k) + c0 + tau_k c1 - a_k for each ElbowAnchorSample a_k (the SDK elbow
//                 carried along the forearm): the kinematic chain inside the gap, where the
//                 strap is hidden but the elbow mostly is not. c0 + tau c1 is the anchor's own
//                 error (the SDK's slowly turning elbow bias), learnt where the strap is seen on
//                 both sides; residuals beyond anchor_huber_k sigma count linearly (the SDK's
//                 jumps and inferred elbows), by reweighting each iteration; a second anchor
//                 (GapRecoveryInput::second_elbow_anchor) the same with its own c0' + tau c1'
//   priors        b_A, e0, e1, c0, c1, c0', c1' (zero mean)
// solved by Gauss-Newton on the sparse normal equations (the sphere and the robust anchor are the
// nonlinear terms).
//
// Why the anchor: on the simulator's body render (bench_table1 --render body --gaps) the 4.4 s
// gap behind the back drifts by 10-20 cm mid-gap although both ends are within 2 cm: the
// accelerations' remaining error after b_A, e0 and e1 is 0.05-0.15 m/s^2 in 0.5 s bins (IMU
// scale and misalignment, attitude), and double integration over T = 4.4 s turns e into up to
// e T^2 / 8. Inertial data alone cannot do better on gaps that long.
#include "forearm/gap_input.hpp"

namespace posefuse::forearm {

struct GapSmootherOptions {
  double boundary_window_s = 0.5;  // visible data used on each side (as II-K.1)
  double acc_sigma_m_s2 = 0.1;     // per-sample net acceleration error (noise + attitude)
  double position_sigma_m = 0.01;  // depth-camera IMU position error
  double sphere_sigma_m = 0.015;   // shoulder position + upper-arm length error
  double bias_prior_sigma_m_s2 = 0.3;
  double leak_prior_sigma_m_s2 = 0.3;  // e0, e1: ~2 degrees of attitude error times g
  bool use_shoulder_sphere = true;
  // The elbow anchor (GapRecoveryInput::elbow_anchor; unused when that is empty). Per sample
  // sigma: the SDK's jitter plus what c0 + tau c1 leaves of its turning bias.
  bool use_elbow_anchor = true;
  double anchor_sigma_m = 0.12;
  double anchor_bias_prior_sigma_m = 0.15;  // c0, c1: the SDK's elbow bias is 5-10 cm
  double anchor_huber_k = 2.0;
  // GapRecoveryInput::second_elbow_anchor (unused when empty), with its own error c0 + tau c1;
  // the same Huber k. Defaults: the camera skeleton's elbow, as anchor_sigma_m above.
  double second_anchor_sigma_m = 0.12;
  double second_anchor_bias_prior_sigma_m = 0.15;
  int max_iterations = 15;
};

// Same output and errors as recover_gap_paper (plus kFailedPrecondition "arm" when the arm
// series does not cover the gap).
RecoveredGap recover_gap_smoother(const GapRecoveryInput& input, const GapSpan& gap,
                                  const GapSmootherOptions& options = {});

}  // namespace posefuse::forearm
