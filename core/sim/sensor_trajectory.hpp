#pragma once
// A sensor's true motion in W, from densely sampled poses, with the derivatives an IMU senses.
//
// Input: poses p_W(t), W_from_A(t) on a uniform grid t0 + k*dt (dt about 1 ms; the scripted
// motions and the body model produce 1 kHz). Derivatives at the grid points by 5-point central
// differences, which are 4th-order accurate:
//   angular rate (body frame A):  r_j = log(W_from_A(t_k)^-1 * W_from_A(t_k + j dt)),
//                                 omega_A(t_k) = (r_-2 - 8 r_-1 + 8 r_1 - r_2) / (12 dt),
//     exact because r(tau) is smooth with r(0) = 0 and dr/dtau(0) = omega_A(t_k);
//     truncation error dt^4/30 * |d^5 r/dtau^5|;
//   acceleration (W):             a_W(t_k) = (-p_-2 + 16 p_-1 - 30 p_0 + 16 p_1 - p_2) / (12 dt^2),
//     truncation error dt^4/90 * |d^6 p/dt^6| (plus rounding ~ 1e-16 |p| / dt^2).
// Between grid points: orientation by slerp, position, rate and acceleration linearly, which
// adds at most dt^2/8 times the second derivative of each (for dt = 1 ms: 1.25e-7 |d2 omega/dt2|
// rad/s; e.g. 4e-6 rad/s for a 1 Hz, 1 rad/s oscillation). The valid range leaves out the two
// grid points at each end that the stencils need.
#include <vector>

#include "geometry/quaternion.hpp"

namespace posefuse::sim {

using geometry::Quat;
using geometry::Vec3;

struct SensorTrajectory {
  double t0_s = 0.0;           // time of the first pose, camera clock seconds
  double dt_s = 0.0;           // grid step, > 0
  std::vector<Vec3> p_W_m;     // sensor origin in W
  std::vector<Quat> W_from_A;  // sensor orientation; unit
};

// What the sensor undergoes at one instant.
struct SensorMotion {
  Quat W_from_A = Quat::Identity();
  Vec3 p_W_m = Vec3::Zero();
  Vec3 omega_A_rad_s = Vec3::Zero();  // angular rate in A
  Vec3 a_W_m_s2 = Vec3::Zero();       // acceleration of the origin in W (gravity excluded)
};

class SensorKinematics {
 public:
  // Validates (kInvalidArgument naming the field: dt_s > 0, at least 6 poses, equal sizes,
  // finite values, unit quaternions within 1e-6, no turn faster than 200 rad/s between
  // neighbours (no body segment turns so fast: a glitch of the input), less than 3 rad of turn
  // over 2 steps, where the logarithm in the rate stencil would alias) and precomputes the
  // derivatives. Fast turns need no denser grid: the stencil is exact for a constant rate
  // about a fixed axis at any step below these bounds.
  explicit SensorKinematics(SensorTrajectory trajectory);

  double t_begin_s() const;  // first time `at` accepts
  double t_end_s() const;    // last time `at` accepts

  // kOutOfRange outside [t_begin_s, t_end_s].
  SensorMotion at(double t_s) const;

  const SensorTrajectory& trajectory() const { return trajectory_; }

 private:
  SensorTrajectory trajectory_;
  std::vector<Vec3> omega_A_;  // per grid point; zero in the two end points each side
  std::vector<Vec3> a_W_;
};

}  // namespace posefuse::sim
