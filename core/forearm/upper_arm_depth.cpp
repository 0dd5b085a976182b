#include "forearm/upper_arm_depth.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "common/error.hpp"
#include "forearm/forearm_axis_depth.hpp"
#include "geometry/point_pca.hpp"
#include "geometry/segment_distance.hpp"

namespace posefuse::forearm {

namespace {

void check_joint(const Vec3& p, const char* field) {
  if (!p.allFinite() || p.z() <= 0.0) throw_invalid(field, "not finite or not in front of the camera");
}

}  // namespace

std::optional<MeasuredUpperArm> measure_upper_arm_axis(const geometry::DepthImageView& depth,
                                                       const geometry::PixelRays& depth_rays, const Vec3& shoulder_K,
                                                       const Vec3& elbow_K, const Vec3& wrist_K,
                                                       const UpperArmAxisOptions& options) {
  const geometry::PinholeCamera& depth_camera = depth_rays.camera();
  if (!depth.pixels || depth.width != depth_camera.width || depth.height != depth_camera.height) {
    throw_invalid("depth.pixels", "missing, or its size differs from the depth camera's");
  }
  check_joint(shoulder_K, "shoulder_K");
  check_joint(elbow_K, "elbow_K");
  check_joint(wrist_K, "wrist_K");
  if ((wrist_K - elbow_K).norm() < 1e-3) throw_invalid("elbow_K/wrist_K", "elbow and wrist coincide");
  if (!(options.search_radius_m > 0.0) || !(options.inlier_radius_m > 0.0) || !(options.forearm_clearance_m >= 0.0) ||
      !(options.elbow_clearance_m >= 0.0) ||
      !(options.shoulder_skip_fraction >= 0.0 && options.shoulder_skip_fraction < 1.0) || options.min_points < 3 ||
      options.refinements < 0) {
    throw_invalid("options",
                  "radii must be positive, shoulder_skip_fraction in [0, 1), min_points >= 3, "
                  "refinements >= 0");
  }
  const Vec3 upper = elbow_K - shoulder_K;
  // Too short to hold a piece of arm, e.g. a straight arm's forearm end found up the upper arm.
  if (upper.norm() < options.min_length_m + options.elbow_clearance_m) return std::nullopt;
  const Vec3 start = shoulder_K + options.shoulder_skip_fraction * upper;
  const std::vector<Vec3> near = depth_points_near_segment(depth, depth_rays, start, elbow_K, options.search_radius_m);
  // Points beside the arm between the cuts across it: from shoulder_skip_fraction of the way from
  // the shoulder to elbow_clearance_m short of the elbow, measured along `direction` (through
  // `point`). A cut across the arm keeps the points symmetric about its axis (distance to the
  // forearm alone would remove more of the side facing the forearm and shift the centroid
  // line); the cuts follow the fitted direction in the second pass, because cuts across the SDK's
  // direction make an oblique piece whose principal axis leans.
  const auto select = [&](const Vec3& point, const Vec3& direction, double max_distance_m) {
    const double a0 = (shoulder_K - point).dot(direction), a1 = (elbow_K - point).dot(direction);
    std::vector<Vec3> kept;
    for (const Vec3& p : near) {
      const Vec3 d = p - point;
      const double along = d.dot(direction);
      if (along < a0 + options.shoulder_skip_fraction * (a1 - a0) || along > a1 - options.elbow_clearance_m) continue;
      if ((d - along * direction).norm() > max_distance_m) continue;
      if (geometry::distance_to_segment(p, elbow_K, wrist_K) <= options.forearm_clearance_m) continue;
      kept.push_back(p);
    }
    return kept;
  };
  std::optional<DepthLine> line = fit_depth_line(select(shoulder_K, upper.normalized(), options.search_radius_m),
                                                 options.inlier_radius_m, options.refinements, options.min_points);
  if (!line) return std::nullopt;
  const Vec3 first_direction = line->direction.dot(upper) < 0.0 ? Vec3(-line->direction) : line->direction;
  line = fit_depth_line(select(line->centroid, first_direction, options.inlier_radius_m), options.inlier_radius_m,
                        options.refinements, options.min_points);
  if (!line) return std::nullopt;
  const Vec3 direction = line->direction.dot(upper) < 0.0 ? Vec3(-line->direction) : line->direction;
  double along_min = 0.0, along_max = 0.0;
  for (std::size_t i = 0; i < line->inliers.size(); ++i) {
    const double along = (line->inliers[i] - line->centroid).dot(direction);
    along_min = i == 0 ? along : std::min(along_min, along);
    along_max = i == 0 ? along : std::max(along_max, along);
  }
  if (along_max - along_min < options.min_length_m) return std::nullopt;
  // A piece cut across a direction other than its own leans towards that direction in a PCA (its
  // scatter is a parallelogram), and the cuts follow a fitted direction: so the direction is
  // taken from the centroids of slices across it instead (each slice of a cylinder's visible
  // surface has its centroid on the surface line, whatever the slice's tilt), the partial end
  // slices left out.
  const int slices = static_cast<int>(std::floor((along_max - along_min) / options.slice_m));
  // Per slice: the points' sum and their lateral coordinate's sum and sum of squares (across the
  // line and the viewing ray), for the slice's own radius below.
  const Vec3 ray = line->centroid.normalized();
  const Vec3 away = (ray - ray.dot(direction) * direction).normalized();
  const Vec3 lateral = direction.cross(away);
  std::vector<Vec3> slice_sum(static_cast<std::size_t>(std::max(slices, 0)), Vec3::Zero());
  std::vector<double> slice_lateral(slice_sum.size(), 0.0), slice_lateral_sq(slice_sum.size(), 0.0);
  std::vector<int> slice_count(slice_sum.size(), 0);
  for (const Vec3& p : line->inliers) {
    const int k = static_cast<int>(((p - line->centroid).dot(direction) - along_min) / options.slice_m);
    if (k >= 1 && k + 1 < slices) {
      const auto i = static_cast<std::size_t>(k);
      slice_sum[i] += p;
      const double x = (p - line->centroid).dot(lateral);
      slice_lateral[i] += x;
      slice_lateral_sq[i] += x * x;
      ++slice_count[i];
    }
  }
  // A real upper arm tapers (deltoid and sleeve: its visible width goes from ~10 to ~7.5 cm on
  // the body render), so its surface line leans towards the camera at the thick end by about the
  // taper, 2-3 degrees, which the arm plane turns into the calibration's roll. With
  // taper_correction each slice's centroid is moved (pi/4) R(s) away from the camera
  // (cylinder_axis' relation per slice), R(s) a straight line fitted by weighted least squares
  // to the slices' radii sqrt(3 var + h^2 / 4): one slice's radius alone is too noisy (a 2 cm
  // slice holds two or three pixel columns at 11 mm pixels).
  struct Slice {
    Vec3 centroid;
    double along, radius_m, weight;
  };
  std::vector<Slice> seen;
  for (std::size_t k = 0; k < slice_sum.size(); ++k) {
    if (slice_count[k] < 3) continue;
    const double n = slice_count[k];
    const Vec3 centroid = slice_sum[k] / n;
    const double mean = slice_lateral[k] / n;
    const double variance = std::max(0.0, slice_lateral_sq[k] / n - mean * mean);
    const double footprint_m = centroid.z() / depth_camera.fx;
    seen.push_back({centroid, (centroid - line->centroid).dot(direction),
                    std::sqrt(3.0 * variance + 0.25 * footprint_m * footprint_m), n});
  }
  double w_sum = 0.0, s_mean = 0.0, r_mean = 0.0;
  for (const Slice& slice : seen) {
    w_sum += slice.weight;
    s_mean += slice.weight * slice.along;
    r_mean += slice.weight * slice.radius_m;
  }
  double taper = 0.0;  // dR / d(along), towards the elbow
  if (seen.size() >= 3) {
    s_mean /= w_sum;
    r_mean /= w_sum;
    double s_var = 0.0, sr_cov = 0.0;
    for (const Slice& slice : seen) {
      s_var += slice.weight * (slice.along - s_mean) * (slice.along - s_mean);
      sr_cov += slice.weight * (slice.along - s_mean) * (slice.radius_m - r_mean);
    }
    if (s_var > 0.0) taper = sr_cov / s_var;
  }
  const bool correct_taper =
      options.taper_correction && line->centroid.z() / depth_camera.fx <= options.max_taper_pixel_m;
  std::vector<Vec3> slice_centroids;
  Vec3 surface_centroid = Vec3::Zero();  // of the slices' centroids, on the surface
  for (const Slice& slice : seen) {
    surface_centroid += slice.centroid;
    const double offset_m = correct_taper ? (std::numbers::pi / 4.0) * taper * (slice.along - s_mean) : 0.0;
    slice_centroids.push_back(slice.centroid + offset_m * away);
  }
  if (slice_centroids.size() < 3) return std::nullopt;
  surface_centroid /= static_cast<double>(slice_centroids.size());
  const geometry::PointPca slice_line = geometry::point_pca(slice_centroids);
  DepthLine centred = *line;
  centred.direction = slice_line.direction().dot(upper) < 0.0 ? Vec3(-slice_line.direction()) : slice_line.direction();
  centred.centroid = surface_centroid;
  const std::optional<CylinderAxis> axis = cylinder_axis(centred, depth_camera.fx);
  if (!axis) return std::nullopt;  // along the viewing ray
  MeasuredUpperArm out;
  out.direction_K = centred.direction;
  out.centroid_K = centred.centroid;
  out.axis_point_K = axis->point;
  out.radius_m = axis->radius_m;
  out.points = static_cast<int>(line->inliers.size());
  return out;
}

std::optional<MeasuredArm> measure_arm_axes(const geometry::DepthImageView& depth,
                                            const geometry::PixelRays& depth_rays, const Vec3& shoulder_K,
                                            const Vec3& elbow_K, const Vec3& wrist_K,
                                            const ForearmAxisOptions& forearm_options,
                                            const UpperArmAxisOptions& upper_arm_options, double min_bend_rad,
                                            double max_elbow_shift_m) {
  // The forearm alone first: its direction (even with some upper arm points in it) tells a bent
  // arm from a straight one better than the SDK's joints. The upper arm is first looked for with
  // the SDK's elbow and wrist for the clearance (that forearm's elbow end may lie up the upper arm).
  std::optional<MeasuredForearmAxis> forearm =
      measure_forearm_axis(depth, depth_rays, elbow_K, wrist_K, forearm_options);
  if (!forearm) return std::nullopt;
  bool excluded = false;
  if (const auto near = measure_upper_arm_axis(depth, depth_rays, shoulder_K, elbow_K, wrist_K, upper_arm_options)) {
    const Vec3 forearm_direction = (forearm->wrist_K - forearm->elbow_K).normalized();
    if (std::acos(std::clamp(near->direction_K.dot(forearm_direction), -1.0, 1.0)) > min_bend_rad) {
      forearm = measure_forearm_axis(depth, depth_rays, elbow_K, wrist_K, forearm_options,
                                     SurfaceLine{near->centroid_K, near->direction_K});
      if (!forearm) return std::nullopt;
      excluded = true;
    }
  }
  MeasuredArm out;
  out.forearm = *forearm;
  out.upper_arm =
      measure_upper_arm_axis(depth, depth_rays, shoulder_K, forearm->elbow_K, forearm->wrist_K, upper_arm_options);
  if (excluded && out.upper_arm) {
    // Closest point of the forearm axis to the upper arm's (both lines, unit directions).
    const Vec3 d1 = (forearm->wrist_K - forearm->elbow_K).normalized(), d2 = out.upper_arm->direction_K;
    const Vec3 w = forearm->elbow_K - out.upper_arm->axis_point_K;
    const double b = d1.dot(d2), denominator = 1.0 - b * b;
    if (denominator > 1e-6) {
      const Vec3 elbow_K = forearm->elbow_K + ((b * d2.dot(w) - d1.dot(w)) / denominator) * d1;
      if ((elbow_K - forearm->elbow_K).norm() <= max_elbow_shift_m) out.forearm.elbow_K = elbow_K;
    }
  }
  return out;
}

}  // namespace posefuse::forearm
