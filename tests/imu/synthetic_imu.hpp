#pragma once
// Synthetic IMU signals for tests: a sensor with a known W_from_A reads
//   acc = A_from_W g_W (specific force, +g up at rest), mag = A_from_W m_W,
// with W x north, y west, z up.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>

#include "imu/imu_sample.hpp"

namespace posefuse::imu::testing {

inline constexpr double kGravity = 9.81;
inline constexpr double kDeg = EIGEN_PI / 180.0;

// Earth field of central Europe: 48 uT, inclination 64 degrees downwards, pointing north.
inline Vec3 earth_field_W() { return 48.0 * Vec3(std::cos(64.0 * kDeg), 0.0, -std::sin(64.0 * kDeg)); }
inline Vec3 up_specific_force_W() { return Vec3(0.0, 0.0, kGravity); }

inline Quat random_orientation(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Quat(n(rng), n(rng), n(rng), n(rng)).normalized();
}

inline Vec3 random_vector(std::mt19937& rng, double sigma) {
  std::normal_distribution<double> n(0.0, sigma);
  return Vec3(n(rng), n(rng), n(rng));
}

// Distance between unit quaternions as rotations (sign-invariant), precise near zero where
// acos of the dot product (angle_between) resolves only ~1e-8 rad. About half the angle.
inline double quat_distance(const Quat& a, const Quat& b) {
  return std::min((a.coeffs() - b.coeffs()).norm(), (a.coeffs() + b.coeffs()).norm());
}

// Noise-free readings of a sensor at W_from_A rotating at `rate_A` (rad/s, sensor frame).
inline ImuSample ideal_sample(std::int64_t t_us, const Quat& W_from_A, const Vec3& rate_A) {
  ImuSample s;
  s.t_us = t_us;
  s.gyr_rad_s = rate_A;
  s.acc_m_s2 = W_from_A.conjugate() * up_specific_force_W();
  s.mag_uT = W_from_A.conjugate() * earth_field_W();
  return s;
}

}  // namespace posefuse::imu::testing
