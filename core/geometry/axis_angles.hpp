#pragma once
// Angles between directions and about an axis, as segment-frame code needs them.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace posefuse::geometry {

// Component of v perpendicular to the unit axis a, normalised (zero when v is along a).
inline Eigen::Vector3d perpendicular(const Eigen::Vector3d& v, const Eigen::Vector3d& a) {
  const Eigen::Vector3d p = v - v.dot(a) * a;
  return p.norm() > 1e-12 ? Eigen::Vector3d(p.normalized()) : Eigen::Vector3d::Zero();
}

// Signed angle (rad) about the unit axis a from u to v (both perpendicular to a).
inline double signed_angle(const Eigen::Vector3d& u, const Eigen::Vector3d& v, const Eigen::Vector3d& a) {
  return std::atan2(a.dot(u.cross(v)), u.dot(v));
}

// Unsigned angle (rad) between two non-zero vectors, accurate near 0 and pi.
inline double angle_between(const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
  return std::atan2(u.cross(v).norm(), u.dot(v));
}

}  // namespace posefuse::geometry
