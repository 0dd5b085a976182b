#include "geometry/quaternion.hpp"

#include <algorithm>
#include <cmath>

namespace posefuse::geometry {

Quat quat_from_rotation_vector(const Vec3& rv) {
  const double angle = rv.norm();
  // sin(a/2)/a by its Taylor series near zero avoids 0/0 and keeps full precision.
  const double half = 0.5 * angle;
  const double sinc_half = angle < 1e-6 ? 0.5 - angle * angle / 48.0 : std::sin(half) / angle;
  return Quat(std::cos(half), sinc_half * rv.x(), sinc_half * rv.y(), sinc_half * rv.z());
}

Vec3 rotation_vector_from_quat(const Quat& q_in) {
  Quat q = q_in.normalized();
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  const double vec_norm = q.vec().norm();
  const double angle = 2.0 * std::atan2(vec_norm, q.w());
  const double scale = vec_norm < 1e-12 ? 2.0 / std::max(q.w(), 1e-300) : angle / vec_norm;
  return scale * q.vec();
}

double angle_between(const Quat& a, const Quat& b) {
  const double dot = std::abs(a.normalized().dot(b.normalized()));
  return 2.0 * std::acos(std::min(1.0, dot));
}

Quat same_hemisphere(const Quat& q, const Quat& reference) {
  if (q.dot(reference) >= 0) return q;
  return Quat(-q.w(), -q.x(), -q.y(), -q.z());
}

}  // namespace posefuse::geometry
