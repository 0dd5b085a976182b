#include "imu/ellipsoid_fit.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include <Eigen/Eigenvalues>

#include "common/error.hpp"

namespace posefuse::imu {

namespace {

using Vec9 = Eigen::Matrix<double, 9, 1>;
using Mat9 = Eigen::Matrix<double, 9, 9>;

Vec9 quadric_row(const Vec3& y) {
  Vec9 row;
  row << y.x() * y.x(), y.y() * y.y(), y.z() * y.z(), 2.0 * y.y() * y.z(), 2.0 * y.x() * y.z(), 2.0 * y.x() * y.y(),
      2.0 * y.x(), 2.0 * y.y(), 2.0 * y.z();
  return row;
}

std::string number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", value);
  return buffer;
}

}  // namespace

Mat3 EllipsoidFit::sphere_from_ellipsoid(double radius) const {
  return radius * axes * radii.cwiseInverse().asDiagonal() * axes.transpose();
}

EllipsoidFit fit_ellipsoid(const std::vector<Vec3>& points, const char* field, double max_condition_number) {
  const std::size_t n = points.size();
  if (n < 9) {
    throw_precondition(field, std::to_string(n) +
                                  " points cannot determine an ellipsoid's 9 coefficients; "
                                  "need at least 9");
  }
  Vec3 mean = Vec3::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    if (!points[i].allFinite()) {
      throw_invalid(std::string(field) + "[" + std::to_string(i) + "]", "not finite");
    }
    mean += points[i];
  }
  mean /= static_cast<double>(n);
  double mean_square_radius = 0.0;
  for (const Vec3& p : points) mean_square_radius += (p - mean).squaredNorm();
  const double scale = std::sqrt(mean_square_radius / static_cast<double>(n));
  if (!(scale > 0.0)) throw_precondition(field, "all points are the same");

  // Normal equations of min |D v - 1|^2 in normalised coordinates y = (p - mean) / scale.
  Mat9 normal = Mat9::Zero();
  Vec9 rhs = Vec9::Zero();
  for (const Vec3& p : points) {
    const Vec9 row = quadric_row((p - mean) / scale);
    normal.selfadjointView<Eigen::Lower>().rankUpdate(row);
    rhs += row;
  }
  normal = normal.selfadjointView<Eigen::Lower>();
  const Eigen::SelfAdjointEigenSolver<Mat9> normal_eigen(normal);
  const double smallest = normal_eigen.eigenvalues()(0);
  const double largest = normal_eigen.eigenvalues()(8);
  EllipsoidFit fit;
  fit.condition_number = smallest > 0.0 ? std::sqrt(largest / smallest) : std::numeric_limits<double>::infinity();
  if (!(fit.condition_number <= max_condition_number)) {
    throw_precondition(field, "the points do not determine an ellipsoid (condition number " +
                                  number(fit.condition_number) + " > " + number(max_condition_number) +
                                  "): their directions are too few, planar or clustered");
  }
  const Vec9 v = normal_eigen.eigenvectors() * (normal_eigen.eigenvalues().cwiseInverse().asDiagonal() *
                                                (normal_eigen.eigenvectors().transpose() * rhs));

  // y^T M y + 2 g^T y = 1  ->  (y - c)^T (M / k) (y - c) = 1 with c = -M^-1 g, k = 1 + c^T M c.
  Mat3 M;
  M << v(0), v(5), v(4), v(5), v(1), v(3), v(4), v(3), v(2);
  const Vec3 g(v(6), v(7), v(8));
  const Eigen::SelfAdjointEigenSolver<Mat3> m_eigen(M);
  const Vec3 m_values = m_eigen.eigenvalues();
  const bool definite = (m_values.array() > 0.0).all() || (m_values.array() < 0.0).all();
  const Vec3 center_y = definite ? Vec3(-M.ldlt().solve(g)) : Vec3::Zero();
  const double k = 1.0 + center_y.dot(M * center_y);
  const Vec3 shape_values = m_values / k;  // eigenvalues of M / k, same eigenvectors
  if (!definite || !(shape_values.array() > 0.0).all() || !shape_values.allFinite()) {
    throw_precondition(field, "the fitted quadric is not an ellipsoid (eigenvalues " + number(shape_values(0)) + ", " +
                                  number(shape_values(1)) + ", " + number(shape_values(2)) + " are not all positive)");
  }
  fit.center = mean + scale * center_y;
  fit.radii = scale * shape_values.cwiseSqrt().cwiseInverse();
  fit.axes = m_eigen.eigenvectors();
  if (fit.axes.determinant() < 0.0) fit.axes.col(2) = -fit.axes.col(2);
  return fit;
}

double relative_norm_spread(const std::vector<Vec3>& points, const Mat3& linear, const Vec3& offset) {
  if (points.empty()) return 0.0;
  double sum = 0.0;
  double sum_sq = 0.0;
  for (const Vec3& p : points) {
    const double r = (linear * (p - offset)).norm();
    sum += r;
    sum_sq += r * r;
  }
  const double count = static_cast<double>(points.size());
  const double mean = sum / count;
  const double variance = std::max(0.0, sum_sq / count - mean * mean);
  return mean > 0.0 ? std::sqrt(variance) / mean : 0.0;
}

}  // namespace posefuse::imu
