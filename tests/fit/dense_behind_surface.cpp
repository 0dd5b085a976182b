#include "dense_behind_surface.hpp"

#include <limits>

namespace posefuse::fit::testing {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// 1D squared distance transform along one line: d[q] = min_p (q - p)^2 + f[p].
void distance_transform_1d(const std::vector<double>& f, int n, std::vector<double>& d, std::vector<int>& v,
                           std::vector<double>& z) {
  int k = -1;
  for (int q = 0; q < n; ++q) {
    if (f[q] == kInf) continue;
    while (k >= 0) {
      const double s = ((f[q] + double(q) * q) - (f[v[k]] + double(v[k]) * v[k])) / (2.0 * (q - v[k]));
      if (s > z[k]) break;
      --k;
    }
    ++k;
    v[k] = q;
    z[k] = k == 0 ? -kInf
                  : ((f[q] + double(q) * q) - (f[v[k - 1]] + double(v[k - 1]) * v[k - 1])) / (2.0 * (q - v[k - 1]));
    z[k + 1] = kInf;
  }
  for (int q = 0, j = 0; q < n; ++q) {
    if (k < 0) {
      d[q] = kInf;
      continue;
    }
    while (z[j + 1] < q) ++j;
    d[q] = double(q - v[j]) * (q - v[j]) + f[v[j]];
  }
}

}  // namespace

std::vector<double> dense_behind_distance2(const BehindSurfaceMap& map) {
  const Eigen::Vector3i size = map.grid_size();
  std::vector<double> dist2(static_cast<size_t>(size.x()) * size.y() * size.z());
  size_t v = 0;
  for (int k = 0; k < size.z(); ++k)
    for (int j = 0; j < size.y(); ++j)
      for (int i = 0; i < size.x(); ++i) dist2[v++] = map.voxel_is_behind(i, j, k) ? 0.0 : kInf;
  const int longest = size.maxCoeff();
  std::vector<double> f(longest), d(longest), z(longest + 1);
  std::vector<int> hull(longest);
  const int axis_size[3] = {size.x(), size.y(), size.z()};
  const size_t stride[3] = {1, static_cast<size_t>(size.x()), static_cast<size_t>(size.x()) * size.y()};
  for (int axis = 0; axis < 3; ++axis) {
    const int n = axis_size[axis];
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
    for (int ib = 0; ib < axis_size[b]; ++ib)
      for (int ia = 0; ia < axis_size[a]; ++ia) {
        const size_t start = ia * stride[a] + ib * stride[b];
        for (int q = 0; q < n; ++q) f[q] = dist2[start + q * stride[axis]];
        distance_transform_1d(f, n, d, hull, z);
        for (int q = 0; q < n; ++q) dist2[start + q * stride[axis]] = d[q];
      }
  }
  return dist2;
}

}  // namespace posefuse::fit::testing
