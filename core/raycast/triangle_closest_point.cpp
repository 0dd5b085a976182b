#include "raycast/triangle_closest_point.hpp"

#include <algorithm>

namespace posefuse::raycast {
namespace {

// Closest point of segment a-b to p as the parameter t in [0, 1].
double segment_parameter(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  return len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
}

}  // namespace

Eigen::Vector3d closest_point_barycentric(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                          const Eigen::Vector3d& c) {
  // Project onto the plane; if the projection lies inside, it is the answer.
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d00 = ab.dot(ab), d01 = ab.dot(ac), d11 = ac.dot(ac);
  const double d20 = ap.dot(ab), d21 = ap.dot(ac);
  const double det = d00 * d11 - d01 * d01;
  if (det > 1e-30) {
    const double wb = (d11 * d20 - d01 * d21) / det, wc = (d00 * d21 - d01 * d20) / det;
    if (wb >= 0 && wc >= 0 && wb + wc <= 1) return {1 - wb - wc, wb, wc};
  }
  // Otherwise it lies on one of the edges: take the nearest of the three.
  const double tab = segment_parameter(p, a, b), tbc = segment_parameter(p, b, c), tca = segment_parameter(p, c, a);
  const Eigen::Vector3d on_ab = a + tab * ab, on_bc = b + tbc * (c - b), on_ca = c + tca * (a - c);
  const double dab = (p - on_ab).squaredNorm(), dbc = (p - on_bc).squaredNorm(), dca = (p - on_ca).squaredNorm();
  if (dab <= dbc && dab <= dca) return {1 - tab, tab, 0};
  if (dbc <= dca) return {0, 1 - tbc, tbc};
  return {tca, 0, 1 - tca};
}

}  // namespace posefuse::raycast
