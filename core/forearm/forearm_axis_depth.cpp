#include "forearm/forearm_axis_depth.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include <Eigen/Eigenvalues>

#include "common/error.hpp"

namespace posefuse::forearm {

namespace {

double distance_to_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double u = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - (a + u * ab)).norm();
}

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

std::optional<MeasuredForearmAxis> measure_forearm_axis(const geometry::DepthImageView& depth,
                                                        const geometry::PinholeCamera& depth_camera,
                                                        const Vec3& elbow_K, const Vec3& wrist_K,
                                                        const ForearmAxisOptions& options) {
  if (!depth.pixels || depth.width != depth_camera.width || depth.height != depth_camera.height) {
    throw_invalid("depth.pixels", "missing, or its size differs from the depth camera's");
  }
  if (!elbow_K.allFinite() || elbow_K.z() <= 0.0) throw_invalid("elbow_K", "not finite or not in front of the camera");
  if (!wrist_K.allFinite() || wrist_K.z() <= 0.0) throw_invalid("wrist_K", "not finite or not in front of the camera");
  if ((wrist_K - elbow_K).norm() < 1e-3) throw_invalid("elbow_K/wrist_K", "elbow and wrist coincide");
  if (!(options.search_radius_m > 0.0) || !(options.inlier_radius_m > 0.0) || !(options.end_margin_m >= 0.0) ||
      options.min_points < 3 || options.refinements < 0) {
    throw_invalid("options", "radii must be positive, min_points >= 3, refinements >= 0");
  }
  const Vec3 sdk_axis = (wrist_K - elbow_K).normalized();
  const Vec3 a = elbow_K - options.end_margin_m * sdk_axis, b = wrist_K + options.end_margin_m * sdk_axis;

  // Pixel window: both extended ends, widened by the search radius at the nearer depth.
  double col0 = depth.width, col1 = -1, row0 = depth.height, row1 = -1;
  double min_z = std::max(1e-3, std::min(a.z(), b.z()) - options.search_radius_m);
  for (const Vec3& end : {a, b}) {
    const Vec3 in_front(end.x(), end.y(), std::max(end.z(), min_z));
    const auto uv = geometry::project(depth_camera, in_front);
    if (!uv) continue;
    col0 = std::min(col0, uv->x());
    col1 = std::max(col1, uv->x());
    row0 = std::min(row0, uv->y());
    row1 = std::max(row1, uv->y());
  }
  if (col1 < col0) return std::nullopt;
  const double margin_px = depth_camera.fx * options.search_radius_m / min_z + 2.0;
  const int c0 = std::max(0, static_cast<int>(std::floor(col0 - margin_px)));
  const int c1 = std::min(depth.width - 1, static_cast<int>(std::ceil(col1 + margin_px)));
  const int r0 = std::max(0, static_cast<int>(std::floor(row0 - margin_px)));
  const int r1 = std::min(depth.height - 1, static_cast<int>(std::ceil(row1 + margin_px)));

  std::vector<Vec3> points;
  for (int row = r0; row <= r1; ++row) {
    for (int col = c0; col <= c1; ++col) {
      const std::uint16_t mm = depth.at(col, row);
      if (mm == 0) continue;
      const Vec3 p = geometry::back_project(depth_camera, col, row, 1e-3 * mm);
      if (distance_to_segment(p, a, b) <= options.search_radius_m) points.push_back(p);
    }
  }
  if (points.size() < static_cast<std::size_t>(options.min_points)) return std::nullopt;

  Line line = principal_line(points);
  for (int i = 0; i < options.refinements; ++i) {
    std::vector<Vec3> inliers;
    for (const Vec3& p : points) {
      const Vec3 d = p - line.centroid;
      if ((d - d.dot(line.direction) * line.direction).norm() <= options.inlier_radius_m) inliers.push_back(p);
    }
    if (inliers.size() < static_cast<std::size_t>(options.min_points)) return std::nullopt;
    points = std::move(inliers);
    line = principal_line(points);
  }
  if (line.direction.dot(sdk_axis) < 0.0) line.direction = -line.direction;

  // Step 3: lateral spread -> R; the axis lies (pi/4) R behind the surface line.
  const Vec3 ray = line.centroid.normalized();
  Vec3 away = ray - ray.dot(line.direction) * line.direction;
  if (away.norm() < 1e-6) return std::nullopt;  // forearm along the viewing ray: no width
  away.normalize();
  const Vec3 lateral = line.direction.cross(away);
  double sum_sq = 0.0, sum = 0.0;
  double along_min = 0.0, along_max = 0.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec3 d = points[i] - line.centroid;
    const double x = d.dot(lateral), along = d.dot(line.direction);
    sum += x;
    sum_sq += x * x;
    along_min = i == 0 ? along : std::min(along_min, along);
    along_max = i == 0 ? along : std::max(along_max, along);
  }
  const double n = static_cast<double>(points.size());
  const double variance = std::max(0.0, sum_sq / n - (sum / n) * (sum / n));
  if (along_max - along_min < options.min_length_m) return std::nullopt;
  MeasuredForearmAxis out;
  // Pixel centres a footprint h apart across a width 2R have variance about R^2 / 3 - h^2 / 12,
  // not R^2 / 3; hence the h^2 / 4 below.
  const double footprint_m = line.centroid.z() / depth_camera.fx;
  out.radius_m = std::sqrt(3.0 * variance + 0.25 * footprint_m * footprint_m);
  const Vec3 axis_point = line.centroid + (std::numbers::pi / 4.0) * out.radius_m * away;
  // The last pixel that sees the forearm lies on average half a pixel's footprint inside its end.
  const auto half_pixel_m = [&](double along) {
    return 0.5 * (axis_point + along * line.direction).z() / depth_camera.fx;
  };
  out.elbow_K = axis_point + (along_min - half_pixel_m(along_min)) * line.direction;
  out.wrist_K = axis_point + (along_max + half_pixel_m(along_max)) * line.direction;
  out.points = static_cast<int>(points.size());
  return out;
}

}  // namespace posefuse::forearm
