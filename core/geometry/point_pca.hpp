#pragma once
// Principal component analysis of a 3D point group: centroid and the scatter's eigenvectors.
// Used for lines and planes in depth data (paper 1, II-F panel groups; II-I strap surface).
#include <vector>

#include "geometry/quaternion.hpp"

namespace posefuse::geometry {

struct PointPca {
  Vec3 centroid = Vec3::Zero();
  // Variances along the axes (mean squared spread, m^2), ascending: [0] is the plane normal's,
  // [2] the line direction's.
  Vec3 variances = Vec3::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // column i belongs to variances[i]
  Vec3 normal() const { return axes.col(0); }
  Vec3 direction() const { return axes.col(2); }
};

// Throws posefuse::Error kInvalidArgument "points" when empty or a point is not finite.
PointPca point_pca(const std::vector<Vec3>& points);

}  // namespace posefuse::geometry
