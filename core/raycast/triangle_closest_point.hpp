#pragma once
// Closest point of a triangle to a point, as barycentric weights (w0, w1, w2) of its corners.
#include <Eigen/Core>

namespace posefuse::raycast {

Eigen::Vector3d closest_point_barycentric(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                          const Eigen::Vector3d& c);

}  // namespace posefuse::raycast
