#pragma once
// Distance from a point to a line segment (depth points near a limb's segment).
#include <algorithm>

#include "geometry/quaternion.hpp"

namespace posefuse::geometry {

// a != b is the caller's to ensure.
inline double distance_to_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double u = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - (a + u * ab)).norm();
}

}  // namespace posefuse::geometry
