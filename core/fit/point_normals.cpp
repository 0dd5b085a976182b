#include "fit/point_normals.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.hpp"

namespace posefuse::fit {

void validate(const NormalParams& params) {
  if (params.window_radius_px < 1 || params.window_radius_px > 64)
    throw_invalid("normal_params.window_radius_px",
                  "must be in [1, 64], got " + std::to_string(params.window_radius_px));
  if (!std::isfinite(params.max_distance_m) || params.max_distance_m <= 0)
    throw_invalid("normal_params.max_distance_m",
                  "must be positive and finite, got " + std::to_string(params.max_distance_m));
  if (params.min_neighbours < 3)
    throw_invalid("normal_params.min_neighbours", "must be at least 3, got " + std::to_string(params.min_neighbours));
}

namespace {

// The gate makes the neighbourhood depend on the centre point, so window sums (integral images)
// cannot give it; the direct loop over the (2r+1)^2 window is exact and fast enough (see
// docs/benchmarks.md). Coordinates are taken relative to the centre to keep the covariance
// accurate in single precision sums.
std::optional<Eigen::Vector3f> normal_at(const PointCloud& cloud, int col, int row, const NormalParams& params) {
  const Eigen::Vector3f& centre = cloud.at(col, row);
  const float max_d2 = params.max_distance_m * params.max_distance_m;
  const int r = params.window_radius_px;
  const int row_lo = std::max(0, row - r), row_hi = std::min(cloud.height - 1, row + r);
  const int col_lo = std::max(0, col - r), col_hi = std::min(cloud.width - 1, col + r);
  int n = 0;
  Eigen::Vector3f sum = Eigen::Vector3f::Zero();
  Eigen::Matrix3f outer = Eigen::Matrix3f::Zero();
  for (int nr = row_lo; nr <= row_hi; ++nr) {
    const size_t base = static_cast<size_t>(nr) * cloud.width;
    for (int nc = col_lo; nc <= col_hi; ++nc) {
      if (!cloud.valid[base + nc]) continue;
      const Eigen::Vector3f d = cloud.value_K[base + nc] - centre;
      if (d.squaredNorm() > max_d2) continue;
      ++n;
      sum += d;
      outer.noalias() += d * d.transpose();
    }
  }
  if (n < params.min_neighbours) return std::nullopt;
  const Eigen::Vector3d mean = sum.cast<double>() / n;
  const Eigen::Matrix3d covariance = outer.cast<double>() / n - mean * mean.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(covariance);
  // Eigenvalues ascend: column 0 is the third principal component.
  Eigen::Vector3f normal = solver.eigenvectors().col(0).cast<float>().normalized();
  if (!normal.allFinite()) return std::nullopt;
  // The camera sits at the origin of K: the normal must point back along the viewing ray.
  if (normal.dot(centre) > 0) normal = -normal;
  return normal;
}

}  // namespace

std::optional<Eigen::Vector3f> estimate_normal_at(const PointCloud& cloud, int col, int row,
                                                  const NormalParams& params) {
  validate(params);
  if (col < 0 || row < 0 || col >= cloud.width || row >= cloud.height)
    throw_invalid("pixel", "(" + std::to_string(col) + ", " + std::to_string(row) + ") is outside the image");
  if (!cloud.has(col, row)) return std::nullopt;
  return normal_at(cloud, col, row, params);
}

std::vector<std::optional<Eigen::Vector3f>> estimate_sample_normals(const PointCloud& cloud,
                                                                    const std::vector<DepthSample>& samples,
                                                                    const NormalParams& params) {
  validate(params);
  std::vector<std::optional<Eigen::Vector3f>> normals;
  normals.reserve(samples.size());
  for (size_t i = 0; i < samples.size(); ++i) {
    const DepthSample& s = samples[i];
    if (s.col < 0 || s.row < 0 || s.col >= cloud.width || s.row >= cloud.height)
      throw_invalid("samples[" + std::to_string(i) + "]",
                    "pixel (" + std::to_string(s.col) + ", " + std::to_string(s.row) + ") is outside the image");
    normals.push_back(cloud.has(s.col, s.row) ? normal_at(cloud, s.col, s.row, params) : std::nullopt);
  }
  return normals;
}

NormalMap estimate_normals(const PointCloud& cloud, const NormalParams& params) {
  validate(params);
  NormalMap map = VectorImage::empty(cloud.width, cloud.height);
  for (int row = 0; row < cloud.height; ++row)
    for (int col = 0; col < cloud.width; ++col) {
      if (!cloud.has(col, row)) continue;
      const auto normal = normal_at(cloud, col, row, params);
      if (!normal) continue;
      map.set(col, row, *normal);
    }
  return map;
}

}  // namespace posefuse::fit
