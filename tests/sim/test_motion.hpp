#pragma once
// Analytic sensor motions for the simulator tests, sampled onto a dense grid.
#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <vector>

#include "imu/imu_sample.hpp"

#include "sim/sensor_trajectory.hpp"

namespace posefuse::sim::testing {

using std::numbers::pi;

inline Quat rot(double angle, const Vec3& axis) { return Quat(Eigen::AngleAxisd(angle, axis)); }

// A "complex" motion: three incommensurate oscillations about z, y, x plus a slow yaw drift,
// rates up to about 8 rad/s, and a position wandering by tens of cm.
inline Quat complex_orientation(double t) {
  const double a = 1.2 * std::sin(2 * pi * 0.7 * t) + 0.5 * t;
  const double b = 0.6 * std::sin(2 * pi * 0.45 * t + 1.0);
  const double c = 1.5 * std::sin(2 * pi * 0.9 * t + 0.3);
  return rot(a, Vec3::UnitZ()) * rot(b, Vec3::UnitY()) * rot(c, Vec3::UnitX());
}

inline Vec3 complex_position(double t) {
  return {0.3 * std::sin(2 * pi * 0.5 * t), 0.2 * std::cos(2 * pi * 0.8 * t), 1.2 + 0.1 * std::sin(2 * pi * 1.1 * t)};
}

// Samples the functions at t0 + k dt for t in [t0, t1].
inline SensorTrajectory sample_trajectory(const std::function<Vec3(double)>& p, const std::function<Quat(double)>& q,
                                          double t0, double t1, double dt = 1e-3) {
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

// Integrates gyro samples at uniform times from q0: the rate between samples is the cubic
// through the four nearest samples (interpolation error ~ h^4), integrated by 16 midpoint
// sub-steps per interval. Both errors are far below what the tests check.
inline Quat integrate_gyro(const std::vector<imu::ImuSample>& samples, const Quat& q0) {
  const std::size_t n = samples.size();
  const double h = 1e-6 * static_cast<double>(samples[1].t_us - samples[0].t_us);
  Quat q = q0;
  constexpr int kSub = 16;
  for (std::size_t k = 0; k + 1 < n; ++k) {
    const std::size_t first = std::min(k > 0 ? k - 1 : 0, n - 4);
    for (int s = 0; s < kSub; ++s) {
      // Position of the sub-step midpoint in units of h, relative to sample `first`.
      const double x = static_cast<double>(k - first) + (s + 0.5) / kSub;
      Vec3 omega = Vec3::Zero();
      for (int i = 0; i < 4; ++i) {
        double weight = 1.0;
        for (int j = 0; j < 4; ++j) {
          if (j != i) weight *= (x - j) / static_cast<double>(i - j);
        }
        omega += weight * samples[first + static_cast<std::size_t>(i)].gyr_rad_s;
      }
      q = (q * geometry::quat_from_rotation_vector(omega * h / kSub)).normalized();
    }
  }
  return q;
}

}  // namespace posefuse::sim::testing
