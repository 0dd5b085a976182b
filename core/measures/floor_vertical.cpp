#include "measures/floor_vertical.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>

#include "common/error.hpp"
#include "geometry/axis_angles.hpp"
#include "geometry/point_pca.hpp"

namespace posefuse::measures {
namespace {

using geometry::Vec3;

constexpr std::uint8_t kBackground = 255;
// Nearer K's y than its x or z: the floor, not a wall (see the header).
const double kMinUpCosine = std::cos(std::numbers::pi / 4);
// Below the camera by at least this: a plane through the camera is no floor to stand on.
constexpr double kMinCameraHeightM = 0.2;

struct Candidate {
  Vec3 p_K;
  int col = 0;
};

void check(const std::vector<std::uint16_t>& depth_mm, const std::vector<std::uint8_t>& body_index,
           const geometry::PinholeCamera& camera, const FloorVerticalOptions& options) {
  geometry::validate(camera, "camera");
  const auto pixels = static_cast<std::size_t>(camera.width) * static_cast<std::size_t>(camera.height);
  if (depth_mm.size() != pixels)
    throw Error(ErrorCode::kInvalidArgument, "depth_mm",
                "has " + std::to_string(depth_mm.size()) + " pixels, the camera " + std::to_string(pixels));
  if (body_index.size() != pixels)
    throw Error(ErrorCode::kInvalidArgument, "body_index",
                "has " + std::to_string(body_index.size()) + " pixels, the camera " + std::to_string(pixels));
  const auto bad = [](const char* field, const std::string& why) {
    throw Error(ErrorCode::kInvalidArgument, std::string("floor_vertical_options.") + field, why);
  };
  if (options.pixel_step < 1) bad("pixel_step", "must be at least 1");
  if (!(options.inlier_distance_m > 0) || !std::isfinite(options.inlier_distance_m))
    bad("inlier_distance_m", "must be positive and finite");
  if (options.min_points < 3) bad("min_points", "must be at least 3");
  if (options.iterations < 1) bad("iterations", "must be at least 1");
}

// The plane n . p = offset with n turned up (the camera, at the origin, above it: offset < 0),
// or none when three points span no plane.
struct Plane {
  Vec3 normal;
  double offset = 0;
};
std::optional<Plane> plane_through(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a);
  if (n.norm() < 1e-9) return std::nullopt;
  Plane plane{n.normalized(), 0};
  plane.offset = plane.normal.dot(a);
  if (plane.offset > 0) plane = {-plane.normal, -plane.offset};
  return plane;
}

bool is_floor(const Plane& plane) { return plane.normal.y() >= kMinUpCosine && -plane.offset >= kMinCameraHeightM; }

// Background pixels whose local surface faces up (see the header, step 1). The sampled pixels
// form a grid (every step-th column and row), and each one's neighbours are grid pixels too, so
// one ray per grid pixel serves every point.
std::vector<Candidate> floor_candidates(const std::vector<std::uint16_t>& depth_mm,
                                        const std::vector<std::uint8_t>& body_index,
                                        const geometry::PinholeCamera& camera, int step) {
  const int width = camera.width;
  const int grid_cols = (camera.width + step - 1) / step, grid_rows = (camera.height + step - 1) / step;
  std::vector<Vec3> ray_z1(static_cast<std::size_t>(grid_cols) * static_cast<std::size_t>(grid_rows));
  for (int gr = 0; gr < grid_rows; ++gr)
    for (int gc = 0; gc < grid_cols; ++gc)
      ray_z1[static_cast<std::size_t>(gr * grid_cols + gc)] = geometry::back_project(camera, gc * step, gr * step, 1.0);
  const auto background_point = [&](int gc, int gr) -> std::optional<Vec3> {
    const std::size_t i =
        static_cast<std::size_t>(gr * step) * static_cast<std::size_t>(width) + static_cast<std::size_t>(gc * step);
    if (depth_mm[i] == 0 || body_index[i] != kBackground) return std::nullopt;
    return Vec3(ray_z1[static_cast<std::size_t>(gr * grid_cols + gc)] * (depth_mm[i] * 1e-3));
  };
  std::vector<Candidate> candidates;
  for (int gr = 0; gr + 1 < grid_rows; ++gr) {
    for (int gc = 0; gc + 1 < grid_cols; ++gc) {
      const auto p = background_point(gc, gr);
      if (!p) continue;
      const auto right = background_point(gc + 1, gr), below = background_point(gc, gr + 1);
      if (!right || !below) continue;
      const auto local = plane_through(*p, *right, *below);
      if (local && local->normal.y() >= kMinUpCosine) candidates.push_back({*p, gc * step});
    }
  }
  return candidates;
}

Vec3 up_normal(const geometry::PointPca& pca) {
  const Vec3 n = pca.normal();
  return n.dot(pca.centroid) > 0 ? Vec3(-n) : n;
}

// The RMS angle of the halves' normals to the whole floor's (see the header, step 3).
double halves_spread_rad(const std::vector<Candidate>& floor, const Vec3& up_K) {
  std::vector<double> cols, depths;
  for (const Candidate& c : floor) {
    cols.push_back(c.col);
    depths.push_back(c.p_K.z());
  }
  const auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  const double mid_col = median(cols), mid_depth = median(depths);
  double sum_sq = 0;
  int halves = 0;
  for (int split = 0; split < 4; ++split) {
    std::vector<Vec3> half;
    for (const Candidate& c : floor) {
      const bool first = split < 2 ? c.col < mid_col : c.p_K.z() < mid_depth;
      if (first == (split % 2 == 0)) half.push_back(c.p_K);
    }
    // A half with fewer than three points spans no plane: the floor is too small to check.
    if (half.size() < 3) return std::numbers::pi / 2;
    const double angle = geometry::angle_between(up_normal(geometry::point_pca(half)), up_K);
    sum_sq += angle * angle;
    ++halves;
  }
  return std::sqrt(sum_sq / halves);
}

}  // namespace

std::optional<FloorVertical> floor_vertical(const std::vector<std::uint16_t>& depth_mm,
                                            const std::vector<std::uint8_t>& body_index,
                                            const geometry::PinholeCamera& camera,
                                            const FloorVerticalOptions& options) {
  check(depth_mm, body_index, camera, options);
  const std::vector<Candidate> candidates = floor_candidates(depth_mm, body_index, camera, options.pixel_step);
  if (candidates.size() < static_cast<std::size_t>(options.min_points)) return std::nullopt;

  std::mt19937 rng(options.seed);
  std::uniform_int_distribution<std::size_t> pick(0, candidates.size() - 1);
  const auto on_plane = [&](const Plane& plane, const Candidate& c) {
    return std::abs(plane.normal.dot(c.p_K) - plane.offset) <= options.inlier_distance_m;
  };
  const auto inliers_of = [&](const Plane& plane) {
    std::vector<Candidate> inliers;
    for (const Candidate& c : candidates)
      if (on_plane(plane, c)) inliers.push_back(c);
    return inliers;
  };
  std::vector<Candidate> best;
  for (int i = 0; i < options.iterations; ++i) {
    const auto plane = plane_through(candidates[pick(rng)].p_K, candidates[pick(rng)].p_K, candidates[pick(rng)].p_K);
    if (!plane || !is_floor(*plane)) continue;
    std::size_t count = 0;
    for (const Candidate& c : candidates) count += on_plane(*plane, c);
    if (count > best.size()) best = inliers_of(*plane);
  }
  if (best.size() < static_cast<std::size_t>(options.min_points)) return std::nullopt;

  // Refit to the inliers of the best draw, take the inliers of that plane, and refit to them.
  const auto fit = [](const std::vector<Candidate>& floor) {
    std::vector<Vec3> points;
    for (const Candidate& c : floor) points.push_back(c.p_K);
    const geometry::PointPca pca = geometry::point_pca(points);
    const Vec3 up = up_normal(pca);
    return Plane{up, up.dot(pca.centroid)};
  };
  const std::vector<Candidate> floor = inliers_of(fit(best));
  if (floor.size() < static_cast<std::size_t>(options.min_points)) return std::nullopt;
  const Plane plane = fit(floor);
  if (!is_floor(plane)) return std::nullopt;
  FloorVertical out;
  out.up_K = plane.normal;
  out.camera_height_m = -plane.offset;
  out.points = static_cast<int>(floor.size());
  out.spread_rad = halves_spread_rad(floor, plane.normal);
  return out;
}

}  // namespace posefuse::measures
