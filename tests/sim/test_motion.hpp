#pragma once
// Analytic sensor motions for the simulator tests, sampled onto a dense grid.
#include <cmath>
#include <functional>

#include "sim/sensor_trajectory.hpp"

namespace posefuse::sim::testing {

constexpr double kPi = 3.14159265358979323846;

inline Quat rot(double angle, const Vec3& axis) { return Quat(Eigen::AngleAxisd(angle, axis)); }

// A "complex" motion: three incommensurate oscillations about z, y, x plus a slow yaw drift,
// rates up to about 8 rad/s, and a position wandering by tens of cm.
inline Quat complex_orientation(double t) {
  const double a = 1.2 * std::sin(2 * kPi * 0.7 * t) + 0.5 * t;
  const double b = 0.6 * std::sin(2 * kPi * 0.45 * t + 1.0);
  const double c = 1.5 * std::sin(2 * kPi * 0.9 * t + 0.3);
  return rot(a, Vec3::UnitZ()) * rot(b, Vec3::UnitY()) * rot(c, Vec3::UnitX());
}

inline Vec3 complex_position(double t) {
  return {0.3 * std::sin(2 * kPi * 0.5 * t), 0.2 * std::cos(2 * kPi * 0.8 * t),
          1.2 + 0.1 * std::sin(2 * kPi * 1.1 * t)};
}

// Samples the functions at t0 + k dt for t in [t0, t1].
inline SensorTrajectory sample_trajectory(const std::function<Vec3(double)>& p,
                                          const std::function<Quat(double)>& q, double t0,
                                          double t1, double dt = 1e-3) {
  SensorTrajectory out;
  out.t0_s = t0;
  out.dt_s = dt;
  const int n = static_cast<int>(std::floor((t1 - t0) / dt + 1e-9)) + 1;
  for (int k = 0; k < n; ++k) {
    const double t = t0 + k * dt;
    out.p_W_m.push_back(p(t));
    out.W_from_A.push_back(q(t).normalized());
  }
  return out;
}

}  // namespace posefuse::sim::testing
