#include "fit/behind_surface_map.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "common/error.hpp"

namespace posefuse::fit {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr uint16_t kNoReading = std::numeric_limits<uint16_t>::max();

// Range of the radial factor L(s) = 1 + k1 s + k2 s^2 + k3 s^3 over s = r^2 in [s0, s1]: the
// end points and the stationary points of the cubic inside.
std::pair<double, double> radial_factor_range(const raycast::DepthIntrinsics& c, double s0, double s1) {
  auto factor = [&](double s) { return 1 + s * (c.k1 + s * (c.k2 + s * c.k3)); };
  double lo = std::min(factor(s0), factor(s1)), hi = std::max(factor(s0), factor(s1));
  auto consider = [&](double s) {
    if (!(s > s0 && s < s1)) return;
    lo = std::min(lo, factor(s));
    hi = std::max(hi, factor(s));
  };
  // L'(s) = k1 + 2 k2 s + 3 k3 s^2.
  const double a = 3 * c.k3, b = 2 * c.k2;
  if (a == 0) {
    if (b != 0) consider(-c.k1 / b);
  } else {
    const double disc = b * b - 4 * a * c.k1;
    if (disc >= 0) {
      consider((-b - std::sqrt(disc)) / (2 * a));
      consider((-b + std::sqrt(disc)) / (2 * a));
    }
  }
  return {lo, hi};
}

// FNV-1a style hash of what voxel classifications depend on: the depth inside `box` (all depth
// lies there) in 64-bit words, the box, the grid and the camera's intrinsics.
uint64_t classification_stamp(const raycast::DepthCamera& camera, const std::vector<uint16_t>& depth_mm,
                              const PixelRect& box, const Eigen::Vector3d& origin, const Eigen::Vector3i& size,
                              double voxel_size) {
  uint64_t h = 1469598103934665603ull;
  auto mix = [&](uint64_t word) {
    h ^= word;
    h *= 1099511628211ull;
    h ^= h >> 29;
  };
  auto mix_double = [&](double v) {
    uint64_t word;
    std::memcpy(&word, &v, sizeof word);
    mix(word);
  };
  for (int row = box.row0; row <= box.row1; ++row) {
    const uint16_t* depth = depth_mm.data() + static_cast<size_t>(row) * camera.width();
    for (int col = box.col0; col <= box.col1; col += 4) {
      uint64_t word = 0;
      for (int k = 0; k < 4 && col + k <= box.col1; ++k) word |= uint64_t(depth[col + k]) << (16 * k);
      mix(word);
    }
  }
  const raycast::DepthIntrinsics& c = camera.intrinsics();
  for (double v : {origin.x(), origin.y(), origin.z(), voxel_size, c.fx, c.fy, c.cx, c.cy, c.k1, c.k2, c.k3})
    mix_double(v);
  for (int v : {size.x(), size.y(), size.z(), c.width, c.height, box.col0, box.row0, box.col1, box.row1})
    mix(static_cast<uint64_t>(v));
  return h | 1;  // never 0, the empty cache's stamp
}

// [min, max] of the products of two intervals.
std::pair<double, double> product_range(double a0, double a1, double b0, double b1) {
  const double p[4] = {a0 * b0, a0 * b1, a1 * b0, a1 * b1};
  return {*std::min_element(p, p + 4), *std::max_element(p, p + 4)};
}
}  // namespace

BehindSurfaceMap::BehindSurfaceMap(const DepthFrame& frame, const raycast::DepthCamera& camera,
                                   const BehindSurfaceParams& params)
    : BehindSurfaceMap(build_point_cloud(frame, camera), camera, params) {}

BehindSurfaceMap::BehindSurfaceMap(const PointCloud& cloud, const raycast::DepthCamera& camera,
                                   const BehindSurfaceParams& params)
    : camera_(&camera) {
  rebuild(cloud, camera, params);
}

void BehindSurfaceMap::rebuild(const PointCloud& cloud, const raycast::DepthCamera& camera,
                               const BehindSurfaceParams& params) {
  if (!std::isfinite(params.voxel_size_m) || params.voxel_size_m <= 0)
    throw_invalid("behind_params.voxel_size_m",
                  "must be positive and finite, got " + std::to_string(params.voxel_size_m));
  if (!std::isfinite(params.margin_m) || params.margin_m < 0)
    throw_invalid("behind_params.margin_m", "must be non-negative and finite, got " + std::to_string(params.margin_m));
  const size_t pixels = static_cast<size_t>(camera.width()) * camera.height();
  if (cloud.width != camera.width() || cloud.height != camera.height() || cloud.valid.size() != pixels ||
      cloud.value_K.size() != pixels)
    throw_invalid("cloud.width", "cloud size does not match the camera");
  if (cloud.count == 0) throw_precondition("frame.body_index", "the silhouette holds no pixel with a depth reading");
  camera_ = &camera;
  voxel_size_m_ = params.voxel_size_m;

  // The depth image and the min pyramid (every level, kNoReading where no pixel has depth).
  // Reused when built for this image size: only the previous cloud's box holds readings, at
  // level l its box >> l, and only that is cleared.
  if (depth_mm_.size() == pixels && !level_size_.empty() &&
      level_size_[0] == Eigen::Vector2i(camera.width(), camera.height())) {
    for (size_t level = 0; level < min_depth_mm_.size(); ++level) {
      const int shift = static_cast<int>(level);
      const int width = level_size_[level].x();
      for (int row = box_.row0 >> shift; row <= box_.row1 >> shift; ++row) {
        const size_t begin = static_cast<size_t>(row) * width + (box_.col0 >> shift);
        const size_t length = static_cast<size_t>((box_.col1 >> shift) - (box_.col0 >> shift) + 1);
        std::fill_n(min_depth_mm_[level].begin() + static_cast<ptrdiff_t>(begin), length, kNoReading);
        if (level == 0) std::fill_n(depth_mm_.begin() + static_cast<ptrdiff_t>(begin), length, kNoDepth);
      }
    }
  } else {
    depth_mm_.assign(pixels, kNoDepth);
    level_size_.assign(1, {camera.width(), camera.height()});
    while (level_size_.back().x() > 1 || level_size_.back().y() > 1)
      level_size_.push_back({(level_size_.back().x() + 1) / 2, (level_size_.back().y() + 1) / 2});
    min_depth_mm_.clear();
    for (const Eigen::Vector2i& size : level_size_)
      min_depth_mm_.emplace_back(static_cast<size_t>(size.x()) * size.y(), kNoReading);
  }
  box_ = cloud.box;

  // Depth (z in mm, as the frame stored it) inside the silhouette and level 0 of the pyramid; the
  // pixel bounding box of the cloud bounds every loop below (nothing outside it has depth).
  std::vector<uint16_t>& level0 = min_depth_mm_[0];
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(kInf), hi = Eigen::Vector3d::Constant(-kInf);
  const int col0 = box_.col0, col1 = box_.col1, row0 = box_.row0, row1 = box_.row1;
  for (int row = row0; row <= row1; ++row)
    for (int col = col0; col <= col1; ++col) {
      const size_t i = static_cast<size_t>(row) * camera.width() + col;
      if (!cloud.valid[i]) continue;
      const Eigen::Vector3d p = cloud.value_K[i].cast<double>();
      // The cloud holds z = depth_mm * 1e-3 (float); rounding recovers the integer millimetres.
      depth_mm_[i] = static_cast<uint16_t>(std::lround(p.z() * 1e3));
      if (depth_mm_[i] != kNoDepth) level0[i] = depth_mm_[i];
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
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

  stamp_ = classification_stamp(camera, depth_mm_, box_, origin_K_, size_, voxel_size_m_);

  for (size_t level = 0; level + 1 < min_depth_mm_.size(); ++level) {
    const int shift = static_cast<int>(level);
    const int fine_width = level_size_[level].x(), coarse_width = level_size_[level + 1].x();
    const std::vector<uint16_t>& below = min_depth_mm_[level];
    std::vector<uint16_t>& next = min_depth_mm_[level + 1];
    // Blocks outside the cloud's box (at this level) hold no reading.
    for (int row = row0 >> shift; row <= row1 >> shift; ++row)
      for (int col = col0 >> shift; col <= col1 >> shift; ++col) {
        uint16_t& m = next[static_cast<size_t>(row / 2) * coarse_width + col / 2];
        m = std::min(m, below[static_cast<size_t>(row) * fine_width + col]);
      }
  }
}

int BehindSurfaceMap::first_possible_layer(const Eigen::Vector3i& lo, const Eigen::Vector3i& hi) const {
  // The voxel centres of the box lie in the axis-aligned box [a, b] in K.
  const Eigen::Vector3d a = voxel_centre_K(lo.x(), lo.y(), lo.z()), b = voxel_centre_K(hi.x(), hi.y(), hi.z());
  if (!(a.z() > 0)) return 0;  // the box reaches the camera plane: no bound
  // Normalised image-aligned coordinates x_n = -x / z, y_n = -y / z (raycast/depth_camera.hpp)
  // over the box: their extremes lie at the corners.
  double xn0 = kInf, xn1 = -kInf, yn0 = kInf, yn1 = -kInf;
  for (double z : {a.z(), b.z()})
    for (double x : {a.x(), b.x()})
      for (double y : {a.y(), b.y()}) {
        xn0 = std::min(xn0, -x / z), xn1 = std::max(xn1, -x / z);
        yn0 = std::min(yn0, -y / z), yn1 = std::max(yn1, -y / z);
      }
  // Distortion scales (x_n, y_n) by L(r^2); bound L over the rectangle's range of r^2.
  const double near_x = xn0 > 0 ? xn0 : (xn1 < 0 ? xn1 : 0.0), near_y = yn0 > 0 ? yn0 : (yn1 < 0 ? yn1 : 0.0);
  const double far_x = std::max(std::abs(xn0), std::abs(xn1)), far_y = std::max(std::abs(yn0), std::abs(yn1));
  const raycast::DepthIntrinsics& c = camera_->intrinsics();
  const auto [l0, l1] = radial_factor_range(c, near_x * near_x + near_y * near_y, far_x * far_x + far_y * far_y);
  auto [xd0, xd1] = product_range(l0, l1, xn0, xn1);
  auto [yd0, yd1] = product_range(l0, l1, yn0, yn1);
  // Tangential distortion shifts by at most 2|p1| |x y| + |p2| (r^2 + 2 x^2) (and its mirror in
  // y) over the rectangle: widen both ranges by that bound.
  if (c.p1 != 0.0 || c.p2 != 0.0) {
    const double r2 = far_x * far_x + far_y * far_y, xy = far_x * far_y;
    const double shift_x = 2 * std::abs(c.p1) * xy + std::abs(c.p2) * (r2 + 2 * far_x * far_x);
    const double shift_y = std::abs(c.p1) * (r2 + 2 * far_y * far_y) + 2 * std::abs(c.p2) * xy;
    xd0 -= shift_x, xd1 += shift_x, yd0 -= shift_y, yd1 += shift_y;
  }
  // Pixels (floor(u + 0.5)) the voxel centres can land on, one pixel of slack for rounding.
  const int col0 = std::max(0, static_cast<int>(std::floor(c.cx + c.fx * xd0 + 0.5)) - 1);
  const int col1 = std::min(camera_->width() - 1, static_cast<int>(std::floor(c.cx + c.fx * xd1 + 0.5)) + 1);
  const int row0 = std::max(0, static_cast<int>(std::floor(c.cy + c.fy * yd0 + 0.5)) - 1);
  const int row1 = std::min(camera_->height() - 1, static_cast<int>(std::floor(c.cy + c.fy * yd1 + 0.5)) + 1);
  if (col0 > col1 || row0 > row1) return size_.z();  // the box is outside the image: nothing behind
  // The coarsest level where the window spans at most 4 x 4 blocks.
  int level = 0;
  while (level + 1 < static_cast<int>(level_size_.size()) && std::max(col1 - col0, row1 - row0) >> level > 3) ++level;
  uint16_t least = kNoReading;
  for (int row = row0 >> level; row <= row1 >> level; ++row)
    for (int col = col0 >> level; col <= col1 >> level; ++col)
      least = std::min(least, min_depth_mm_[level][static_cast<size_t>(row) * level_size_[level].x() + col]);
  if (least == kNoReading) return size_.z();
  // Voxels with centre z below least * 1e-3 are in front of every depth they can project onto;
  // one layer of slack keeps the bound safe against rounding.
  return std::max(0, static_cast<int>(std::floor((least * 1e-3 - origin_K_.z()) / voxel_size_m_)) - 1);
}

uint16_t BehindSurfaceMap::depth_at(const Eigen::Vector3d& p_K) const {
  const auto uv = camera_->project(p_K);
  if (!uv) return kNoDepth;
  // Pixel c covers image coordinates [c - 0.5, c + 0.5) (centres at integers).
  const int col = static_cast<int>(std::floor(uv->x() + 0.5)), row = static_cast<int>(std::floor(uv->y() + 0.5));
  if (col < 0 || row < 0 || col >= camera_->width() || row >= camera_->height()) return kNoDepth;
  return depth_mm_[static_cast<size_t>(row) * camera_->width() + col];
}

bool BehindSurfaceMap::is_behind(const Eigen::Vector3d& p_K) const {
  const uint16_t depth = depth_at(p_K);
  return depth != kNoDepth && p_K.z() >= depth * 1e-3;
}

Eigen::Vector3i BehindSurfaceMap::voxel_of(const Eigen::Vector3d& p_K) const {
  // Clamp in floating point before the cast so that far-away points cannot overflow int.
  return ((p_K - origin_K_) / voxel_size_m_)
      .array()
      .round()
      .max(0.0)
      .min((size_.array() - 1).cast<double>())
      .cast<int>();
}

Eigen::Vector3d BehindSurfaceMap::closest_behind(const Eigen::Vector3d& p_K) const { return search(p_K, nullptr); }

Eigen::Vector3d BehindSurfaceMap::closest_behind(const Eigen::Vector3d& p_K, BehindSurfaceCache& cache) const {
  const size_t voxels = static_cast<size_t>(size_.x()) * size_.y() * size_.z();
  if (cache.map_stamp_ != stamp_ || cache.state_.size() != voxels) {
    cache.state_.assign(voxels, 0);
    cache.map_stamp_ = stamp_;
  }
  return search(p_K, &cache);
}

Eigen::Vector3d BehindSurfaceMap::search(const Eigen::Vector3d& p_K, BehindSurfaceCache* cache) const {
  if (!p_K.allFinite()) throw_invalid("p_K", "not finite");
  if (is_behind(p_K)) return p_K;
  const Eigen::Vector3i c = voxel_of(p_K);
  // Shells of Chebyshev radius r hold only voxels at squared grid distance >= r^2, so once the
  // best squared distance found is <= r^2 no later shell can beat it: the result is a nearest
  // behind voxel of the whole grid, as a full distance transform would give.
  const int max_radius =
      std::max({c.x(), size_.x() - 1 - c.x(), c.y(), size_.y() - 1 - c.y(), c.z(), size_.z() - 1 - c.z()});
  int64_t best_d2 = std::numeric_limits<int64_t>::max();
  Eigen::Vector3i best(-1, -1, -1);
  // 0 = not classified yet, 1 = not behind, 2 = behind.
  auto behind = [&](const Eigen::Vector3i& v) {
    if (!cache) return voxel_is_behind(v.x(), v.y(), v.z());
    uint8_t& state = cache->state_[(static_cast<size_t>(v.z()) * size_.y() + v.y()) * size_.x() + v.x()];
    if (state == 0) state = voxel_is_behind(v.x(), v.y(), v.z()) ? 2 : 1;
    return state == 2;
  };
  auto consider = [&](int di, int dj, int dk) {
    const int64_t d2 = int64_t(di) * di + int64_t(dj) * dj + int64_t(dk) * dk;
    if (d2 >= best_d2) return;
    const Eigen::Vector3i v(c.x() + di, c.y() + dj, c.z() + dk);
    if (!behind(v)) return;
    best_d2 = d2;
    best = v;
  };
  // (1) An upper bound: a float point (paper 2, Eq. 12) projects onto a pixel with depth d and
  // lies in front of it, so the voxels around its ray at depth d and a little beyond are usually
  // behind; otherwise the voxels straight behind the query's.
  auto try_bound = [&](const Eigen::Vector3i& v) {
    const int64_t d2 = (v - c).cast<int64_t>().squaredNorm();
    if (d2 >= best_d2 || !behind(v)) return false;
    best_d2 = d2;
    best = v;
    return true;
  };
  if (const uint16_t depth = depth_at(p_K); depth != kNoDepth && p_K.z() > 0) {
    for (int step = 0; step < 4; ++step)
      if (try_bound(voxel_of(p_K * ((depth * 1e-3 + step * 0.5 * voxel_size_m_) / p_K.z())))) break;
  }
  if (best.x() < 0)
    for (int k = c.z(); k < size_.z(); ++k)
      if (try_bound({c.x(), c.y(), k})) break;
  // (2) Layers that can hold a behind voxel within that bound.
  Eigen::Vector3i box_lo = Eigen::Vector3i::Zero(), box_hi = size_.array() - 1;
  if (best.x() >= 0) {
    const int reach = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(best_d2))));
    box_lo = box_lo.cwiseMax((c.array() - reach).matrix());
    box_hi = box_hi.cwiseMin((c.array() + reach).matrix());
  }
  const int first_layer = first_possible_layer(box_lo, box_hi);
  // (3) Shells in those layers.
  for (int r = std::max(0, first_layer - c.z()); r <= max_radius && best_d2 > int64_t(r) * r; ++r) {
    const int k_lo = std::max({-r, -c.z(), first_layer - c.z()}), k_hi = std::min(r, size_.z() - 1 - c.z());
    const int j_lo = std::max(-r, -c.y()), j_hi = std::min(r, size_.y() - 1 - c.y());
    const int i_lo = std::max(-r, -c.x()), i_hi = std::min(r, size_.x() - 1 - c.x());
    for (int dk = k_lo; dk <= k_hi; ++dk)
      for (int dj = j_lo; dj <= j_hi; ++dj) {
        if (std::abs(dk) == r || std::abs(dj) == r) {
          for (int di = i_lo; di <= i_hi; ++di) consider(di, dj, dk);
        } else {
          if (-r >= i_lo) consider(-r, dj, dk);
          if (r <= i_hi && r > 0) consider(r, dj, dk);
        }
      }
  }
  if (best.x() < 0) throw_precondition("behind_surface_map", "no voxel lies behind the observed surface");
  return voxel_centre_K(best.x(), best.y(), best.z());
}

}  // namespace posefuse::fit
