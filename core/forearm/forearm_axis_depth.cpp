#include "forearm/forearm_axis_depth.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include <Eigen/Eigenvalues>

#include "common/error.hpp"

namespace posefuse::forearm {

namespace {

struct Line {
  Vec3 centroid;
  Vec3 direction;  // unit
};

Line principal_line(const std::vector<Vec3>& points) {
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& p : points) centroid += p;
  centroid /= static_cast<double>(points.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Vec3& p : points) scatter += (p - centroid) * (p - centroid).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(scatter);
  return {centroid, solver.eigenvectors().col(2).normalized()};  // largest eigenvalue last
}

}  // namespace

std::vector<Vec3> depth_points_near_segment(const geometry::DepthImageView& depth,
                                            const geometry::PixelRays& depth_rays, const Vec3& a, const Vec3& b,
                                            double radius_m) {
  const geometry::PinholeCamera& depth_camera = depth_rays.camera();
  if (!depth.pixels || depth.width != depth_camera.width || depth.height != depth_camera.height) {
    throw_invalid("depth.pixels", "missing, or its size differs from the depth camera's");
  }
  // Pixel window: both extended ends, widened by the search radius at the nearer depth.
  double col0 = depth.width, col1 = -1, row0 = depth.height, row1 = -1;
  double min_z = std::max(1e-3, std::min(a.z(), b.z()) - radius_m);
  for (const Vec3& end : {a, b}) {
    const Vec3 in_front(end.x(), end.y(), std::max(end.z(), min_z));
    const auto uv = geometry::project(depth_camera, in_front);
    if (!uv) continue;
    col0 = std::min(col0, uv->x());
    col1 = std::max(col1, uv->x());
    row0 = std::min(row0, uv->y());
    row1 = std::max(row1, uv->y());
  }
  if (col1 < col0) return {};
  const double margin_px = depth_camera.fx * radius_m / min_z + 2.0;
  const int c0 = std::max(0, static_cast<int>(std::floor(col0 - margin_px)));
  const int c1 = std::min(depth.width - 1, static_cast<int>(std::ceil(col1 + margin_px)));
  const int r0 = std::max(0, static_cast<int>(std::floor(row0 - margin_px)));
  const int r1 = std::min(depth.height - 1, static_cast<int>(std::ceil(row1 + margin_px)));

  // geometry::distance_to_segment's arithmetic with the segment's parts hoisted out of the loop,
  // and a depth outside the segment's depth range +- radius_m rejected first (most of the window
  // is background or torso): the same points as testing each one in full.
  const Vec3 ab = b - a;
  const double ab_squared = ab.squaredNorm();
  const double z_low = std::min(a.z(), b.z()) - radius_m, z_high = std::max(a.z(), b.z()) + radius_m;
  std::vector<Vec3> points;
  for (int row = r0; row <= r1; ++row) {
    const std::uint16_t* depth_row = depth.pixels + static_cast<std::ptrdiff_t>(row) * depth.width;
    for (int col = c0; col <= c1; ++col) {
      const std::uint16_t mm = depth_row[col];
      if (mm == 0) continue;
      const double z = 1e-3 * mm;
      if (z < z_low || z > z_high) continue;
      const Vec3 p = depth_rays.point(col, row, z);
      const double u = std::clamp((p - a).dot(ab) / ab_squared, 0.0, 1.0);
      if ((p - (a + u * ab)).norm() <= radius_m) points.push_back(p);
    }
  }
  return points;
}

std::optional<DepthLine> fit_depth_line(std::vector<Vec3> points, double inlier_radius_m, int refinements,
                                        int min_points) {
  if (points.size() < static_cast<std::size_t>(min_points)) return std::nullopt;
  Line line = principal_line(points);
  for (int i = 0; i < refinements; ++i) {
    std::vector<Vec3> inliers;
    for (const Vec3& p : points) {
      const Vec3 d = p - line.centroid;
      if ((d - d.dot(line.direction) * line.direction).norm() <= inlier_radius_m) inliers.push_back(p);
    }
    if (inliers.size() < static_cast<std::size_t>(min_points)) return std::nullopt;
    points = std::move(inliers);
    line = principal_line(points);
  }
  return DepthLine{line.centroid, line.direction, std::move(points)};
}

std::optional<CylinderAxis> cylinder_axis(const DepthLine& line, double depth_fx) {
  // Step 3: lateral spread -> R; the axis lies (pi/4) R behind the surface line.
  const Vec3 ray = line.centroid.normalized();
  Vec3 away = ray - ray.dot(line.direction) * line.direction;
  if (away.norm() < 1e-6 || line.inliers.empty()) return std::nullopt;
  away.normalize();
  const Vec3 lateral = line.direction.cross(away);
  CylinderAxis out;
  out.direction = line.direction;
  double sum_sq = 0.0, sum = 0.0;
  for (std::size_t i = 0; i < line.inliers.size(); ++i) {
    const Vec3 d = line.inliers[i] - line.centroid;
    const double x = d.dot(lateral), along = d.dot(line.direction);
    sum += x;
    sum_sq += x * x;
    out.along_min = i == 0 ? along : std::min(out.along_min, along);
    out.along_max = i == 0 ? along : std::max(out.along_max, along);
  }
  const double n = static_cast<double>(line.inliers.size());
  const double variance = std::max(0.0, sum_sq / n - (sum / n) * (sum / n));
  // Pixel centres a footprint h apart across a width 2R have variance about R^2 / 3 - h^2 / 12,
  // not R^2 / 3; hence the h^2 / 4 below.
  const double footprint_m = line.centroid.z() / depth_fx;
  out.radius_m = std::sqrt(3.0 * variance + 0.25 * footprint_m * footprint_m);
  out.point = line.centroid + (std::numbers::pi / 4.0) * out.radius_m * away;
  return out;
}

std::optional<double> wrist_from_width_profile(const std::vector<double>& along, const std::vector<double>& lateral,
                                               double along_max, const ForearmAxisOptions& options) {
  const double start = along_max - options.hand_max_m - 2.0 * options.slice_m;
  const int slices = static_cast<int>(std::ceil((along_max - start) / options.slice_m));
  if (slices < 5) return std::nullopt;
  std::vector<double> sum(static_cast<std::size_t>(slices), 0.0), sum_sq(sum.size(), 0.0), count(sum.size(), 0.0);
  for (std::size_t i = 0; i < along.size(); ++i) {
    const int k = static_cast<int>(std::floor((along[i] - start) / options.slice_m));
    if (k < 0 || k >= slices) continue;
    sum[static_cast<std::size_t>(k)] += lateral[i];
    sum_sq[static_cast<std::size_t>(k)] += lateral[i] * lateral[i];
    count[static_cast<std::size_t>(k)] += 1.0;
  }
  std::vector<double> width(sum.size(), -1.0);
  for (std::size_t k = 0; k < sum.size(); ++k) {
    if (count[k] < 3.0) continue;
    const double mean = sum[k] / count[k];
    width[k] = std::sqrt(12.0 * std::max(0.0, sum_sq[k] / count[k] - mean * mean));
  }
  // Three-slice average where all three are seen.
  std::vector<double> smooth(width.size(), -1.0);
  for (std::size_t k = 1; k + 1 < width.size(); ++k) {
    if (width[k - 1] >= 0.0 && width[k] >= 0.0 && width[k + 1] >= 0.0) {
      smooth[k] = (width[k - 1] + width[k] + width[k + 1]) / 3.0;
    }
  }
  const auto centre = [&](std::size_t k) { return start + (static_cast<double>(k) + 0.5) * options.slice_m; };
  double narrowest = INFINITY;
  for (std::size_t k = 0; k < smooth.size(); ++k) {
    const double c = centre(k);
    if (smooth[k] >= 0.0 && c >= along_max - options.hand_max_m && c <= along_max - options.hand_min_m) {
      narrowest = std::min(narrowest, smooth[k]);
    }
  }
  if (!std::isfinite(narrowest)) return std::nullopt;
  std::optional<double> wrist;
  for (std::size_t k = 0; k < smooth.size(); ++k) {
    const double c = centre(k);
    if (smooth[k] >= 0.0 && c >= along_max - options.hand_max_m && c <= along_max - options.hand_min_m &&
        smooth[k] <= narrowest + options.width_tolerance_m) {
      wrist = c + 0.5 * options.slice_m;  // the slice's distal edge
    }
  }
  // A hand must be seen beyond: some slice there wider than the wrist by hand_widening_m (a bare
  // cylinder, or a hand seen end-on, has none; then the distal end stands).
  double widest_beyond = -1.0;
  for (std::size_t k = 0; wrist && k < smooth.size(); ++k) {
    if (centre(k) > *wrist) widest_beyond = std::max(widest_beyond, smooth[k]);
  }
  if (!wrist || widest_beyond < narrowest + options.hand_widening_m) return std::nullopt;
  return wrist;
}

std::optional<MeasuredForearmAxis> measure_forearm_axis(const geometry::DepthImageView& depth,
                                                        const geometry::PixelRays& depth_rays, const Vec3& elbow_K,
                                                        const Vec3& wrist_K, const ForearmAxisOptions& options,
                                                        const std::optional<SurfaceLine>& excluded) {
  const geometry::PinholeCamera& depth_camera = depth_rays.camera();
  if (!depth.pixels || depth.width != depth_camera.width || depth.height != depth_camera.height) {
    throw_invalid("depth.pixels", "missing, or its size differs from the depth camera's");
  }
  if (!elbow_K.allFinite() || elbow_K.z() <= 0.0) throw_invalid("elbow_K", "not finite or not in front of the camera");
  if (!wrist_K.allFinite() || wrist_K.z() <= 0.0) throw_invalid("wrist_K", "not finite or not in front of the camera");
  if ((wrist_K - elbow_K).norm() < 1e-3) throw_invalid("elbow_K/wrist_K", "elbow and wrist coincide");
  if (!(options.search_radius_m > 0.0) || !(options.inlier_radius_m > 0.0) || !(options.end_margin_m >= 0.0) ||
      options.min_points < 3 || options.refinements < 0 || !(options.slice_m > 0.0) ||
      !(options.hand_min_m >= 0.0 && options.hand_min_m < options.hand_max_m) || !(options.width_tolerance_m >= 0.0) ||
      !(options.hand_widening_m >= 0.0) || !(options.max_width_pixel_m > 0.0)) {
    throw_invalid("options",
                  "radii and slice_m must be positive, min_points >= 3, refinements >= 0, "
                  "0 <= hand_min_m < hand_max_m, width_tolerance_m and hand_widening_m >= 0");
  }
  if (excluded && (!excluded->point.allFinite() || !excluded->direction.allFinite() ||
                   std::abs(excluded->direction.norm() - 1.0) > 1e-6)) {
    throw_invalid("excluded", "not a finite point and unit direction");
  }
  const Vec3 sdk_axis = (wrist_K - elbow_K).normalized();
  const Vec3 a = elbow_K - options.end_margin_m * sdk_axis, b = wrist_K + options.end_margin_m * sdk_axis;
  std::vector<Vec3> points = depth_points_near_segment(depth, depth_rays, a, b, options.search_radius_m);
  if (excluded) {
    std::erase_if(points, [&](const Vec3& p) {
      const Vec3 d = p - excluded->point;
      return (d - d.dot(excluded->direction) * excluded->direction).norm() <= options.excluded_radius_m;
    });
  }
  const std::optional<DepthLine> fitted =
      fit_depth_line(std::move(points), options.inlier_radius_m, options.refinements, options.min_points);
  if (!fitted) return std::nullopt;
  DepthLine line = *fitted;
  if (line.direction.dot(sdk_axis) < 0.0) line.direction = -line.direction;

  const std::optional<CylinderAxis> axis = cylinder_axis(line, depth_camera.fx);
  if (!axis) return std::nullopt;  // forearm along the viewing ray: no width
  if (axis->along_max - axis->along_min < options.min_length_m) return std::nullopt;
  MeasuredForearmAxis out;
  out.radius_m = axis->radius_m;
  // The last pixel that sees the forearm lies on average half a pixel's footprint inside its end.
  const auto half_pixel_m = [&](double along) {
    return 0.5 * (axis->point + along * axis->direction).z() / depth_camera.fx;
  };
  out.elbow_K = axis->point + (axis->along_min - half_pixel_m(axis->along_min)) * axis->direction;
  out.wrist_K = axis->point + (axis->along_max + half_pixel_m(axis->along_max)) * axis->direction;
  out.points = static_cast<int>(line.inliers.size());
  // The width profile needs the wrist's narrowing resolved: 1-2 cm on a 5 cm wrist are 1-2
  // pixels at max_width_pixel_m; coarser pixels alias whole centimetres into the slices' widths.
  if (options.wrist_from_width && axis->point.z() / depth_camera.fx <= options.max_width_pixel_m) {
    const Vec3 ray = axis->point.normalized();
    const Vec3 lateral_direction = axis->direction.cross(ray).normalized();
    std::vector<double> along, lateral;
    for (const Vec3& p : line.inliers) {
      along.push_back((p - axis->point).dot(axis->direction));
      lateral.push_back((p - axis->point).dot(lateral_direction));
    }
    if (const auto wrist = wrist_from_width_profile(along, lateral, axis->along_max, options)) {
      if (*wrist - axis->along_min >= options.min_length_m) out.wrist_K = axis->point + *wrist * axis->direction;
    }
  }
  return out;
}

}  // namespace posefuse::forearm
