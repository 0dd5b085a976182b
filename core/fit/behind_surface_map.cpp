#include "fit/behind_surface_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "common/error.hpp"

namespace posefuse::fit {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// 1D squared distance transform along one line (Felzenszwalb & Huttenlocher 2012): for each
// position q, min_p (q - p)^2 + f[p] and its argmin p. Scratch buffers are passed in to avoid
// reallocating per line.
void distance_transform_1d(const std::vector<double>& f, int n, std::vector<double>& d, std::vector<int>& arg,
                           std::vector<int>& v, std::vector<double>& z) {
  int k = -1;
  for (int q = 0; q < n; ++q) {
    if (f[q] == kInf) continue;
    while (k >= 0) {
      const double s = ((f[q] + double(q) * q) - (f[v[k]] + double(v[k]) * v[k])) / (2.0 * (q - v[k]));
      if (s <= z[k]) {
        --k;
      } else {
        break;
      }
    }
    ++k;
    v[k] = q;
    z[k] = k == 0 ? -kInf : ((f[q] + double(q) * q) - (f[v[k - 1]] + double(v[k - 1]) * v[k - 1])) / (2.0 * (q - v[k - 1]));
    z[k + 1] = kInf;
  }
  if (k < 0) {
    std::fill(d.begin(), d.begin() + n, kInf);
    std::fill(arg.begin(), arg.begin() + n, -1);
    return;
  }
  int j = 0;
  for (int q = 0; q < n; ++q) {
    while (z[j + 1] < q) ++j;
    d[q] = double(q - v[j]) * (q - v[j]) + f[v[j]];
    arg[q] = v[j];
  }
}

}  // namespace

BehindSurfaceMap::BehindSurfaceMap(const DepthFrame& frame, const raycast::DepthCamera& camera,
                                   const BehindSurfaceParams& params)
    : camera_(&camera), voxel_size_m_(params.voxel_size_m) {
  if (!std::isfinite(params.voxel_size_m) || params.voxel_size_m <= 0)
    throw_invalid("behind_params.voxel_size_m", "must be positive and finite, got " + std::to_string(params.voxel_size_m));
  if (!std::isfinite(params.margin_m) || params.margin_m < 0)
    throw_invalid("behind_params.margin_m", "must be non-negative and finite, got " + std::to_string(params.margin_m));
  const PointCloud cloud = build_point_cloud(frame, camera);

  depth_mm_.assign(cloud.valid.size(), kNoDepth);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(kInf), hi = Eigen::Vector3d::Constant(-kInf);
  for (size_t i = 0; i < cloud.valid.size(); ++i) {
    if (!cloud.valid[i]) continue;
    depth_mm_[i] = frame.depth_mm[i];
    lo = lo.cwiseMin(cloud.value_K[i].cast<double>());
    hi = hi.cwiseMax(cloud.value_K[i].cast<double>());
  }
  lo -= Eigen::Vector3d::Constant(params.margin_m);
  hi += Eigen::Vector3d::Constant(params.margin_m);
  origin_K_ = lo;
  size_ = ((hi - lo) / voxel_size_m_).array().floor().cast<int>() + 1;
  const int64_t voxels = int64_t(size_.x()) * size_.y() * size_.z();
  if (voxels > params.max_voxels)
    throw Error(ErrorCode::kResourceExhausted, "behind_params.max_voxels",
                "the cloud's bounding box needs " + std::to_string(voxels) + " voxels, limit " +
                    std::to_string(params.max_voxels));

  voxel_behind_.assign(static_cast<size_t>(voxels), 0);
  for (int k = 0; k < size_.z(); ++k)
    for (int j = 0; j < size_.y(); ++j)
      for (int i = 0; i < size_.x(); ++i) voxel_behind_[index(i, j, k)] = is_behind(voxel_centre_K(i, j, k));

  // Separable exact EDT over x, then y, then z; `nearest_behind_` follows the argmin of each pass.
  std::vector<double> dist2(static_cast<size_t>(voxels));
  nearest_behind_.assign(static_cast<size_t>(voxels), -1);
  for (size_t v = 0; v < dist2.size(); ++v) {
    dist2[v] = voxel_behind_[v] ? 0.0 : kInf;
    if (voxel_behind_[v]) nearest_behind_[v] = static_cast<int32_t>(v);
  }
  const int longest = size_.maxCoeff();
  std::vector<double> f(longest), d(longest), z(longest + 1);
  std::vector<int> arg(longest), hull(longest);
  std::vector<int32_t> line_nearest(longest);
  const int axis_size[3] = {size_.x(), size_.y(), size_.z()};
  const size_t stride[3] = {1, static_cast<size_t>(size_.x()), static_cast<size_t>(size_.x()) * size_.y()};
  for (int axis = 0; axis < 3; ++axis) {
    const int n = axis_size[axis];
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
    for (int ib = 0; ib < axis_size[b]; ++ib)
      for (int ia = 0; ia < axis_size[a]; ++ia) {
        const size_t start = ia * stride[a] + ib * stride[b];
        for (int q = 0; q < n; ++q) {
          f[q] = dist2[start + q * stride[axis]];
          line_nearest[q] = nearest_behind_[start + q * stride[axis]];
        }
        distance_transform_1d(f, n, d, arg, hull, z);
        for (int q = 0; q < n; ++q) {
          dist2[start + q * stride[axis]] = d[q];
          nearest_behind_[start + q * stride[axis]] = arg[q] < 0 ? -1 : line_nearest[arg[q]];
        }
      }
  }
}

bool BehindSurfaceMap::is_behind(const Eigen::Vector3d& p_K) const {
  const auto uv = camera_->project(p_K);
  if (!uv) return false;
  // Pixel c covers image coordinates [c - 0.5, c + 0.5) (centres at integers).
  const int col = static_cast<int>(std::floor(uv->x() + 0.5)), row = static_cast<int>(std::floor(uv->y() + 0.5));
  if (col < 0 || row < 0 || col >= camera_->width() || row >= camera_->height()) return false;
  const uint16_t depth = depth_mm_[static_cast<size_t>(row) * camera_->width() + col];
  return depth != kNoDepth && p_K.z() >= depth * 1e-3;
}

Eigen::Vector3d BehindSurfaceMap::closest_behind(const Eigen::Vector3d& p_K) const {
  if (!p_K.allFinite()) throw_invalid("p_K", "not finite");
  if (is_behind(p_K)) return p_K;
  // Clamp in floating point before the cast so that far-away points cannot overflow int.
  const Eigen::Vector3i cell = ((p_K - origin_K_) / voxel_size_m_)
                                   .array()
                                   .round()
                                   .max(0.0)
                                   .min((size_.array() - 1).cast<double>())
                                   .cast<int>();
  const int32_t nearest = nearest_behind_[index(cell.x(), cell.y(), cell.z())];
  if (nearest < 0) throw_precondition("behind_surface_map", "no voxel lies behind the observed surface");
  const int i = nearest % size_.x(), j = (nearest / size_.x()) % size_.y(), k = nearest / (size_.x() * size_.y());
  return voxel_centre_K(i, j, k);
}

}  // namespace posefuse::fit
