#include "geometry/point_pca.hpp"

#include <Eigen/Eigenvalues>

#include "common/error.hpp"

namespace posefuse::geometry {

PointPca point_pca(const std::vector<Vec3>& points) {
  if (points.empty()) throw_invalid("points", "no points");
  PointPca out;
  for (const Vec3& p : points) {
    if (!p.allFinite()) throw_invalid("points", "a point is not finite");
    out.centroid += p;
  }
  const double n = static_cast<double>(points.size());
  out.centroid /= n;
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Vec3& p : points) scatter += (p - out.centroid) * (p - out.centroid).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(scatter / n);
  out.variances = eigen.eigenvalues().cwiseMax(0.0);  // ascending
  out.axes = eigen.eigenvectors();
  return out;
}

}  // namespace posefuse::geometry
