#include "forearm/strap_detection.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "geometry/point_pca.hpp"

namespace posefuse::forearm {

namespace {

double bilinear(const GrayImageView& image, const Vec2& uv) {
  const double u = std::clamp(uv.x(), 0.0, image.width - 1.0);
  const double v = std::clamp(uv.y(), 0.0, image.height - 1.0);
  const int u0 = std::min(static_cast<int>(u), image.width - 2 < 0 ? 0 : image.width - 2);
  const int v0 = std::min(static_cast<int>(v), image.height - 2 < 0 ? 0 : image.height - 2);
  const int u1 = std::min(u0 + 1, image.width - 1), v1 = std::min(v0 + 1, image.height - 1);
  const double fu = u - u0, fv = v - v0;
  const auto at = [&](int x, int y) { return static_cast<double>(image.pixels[y * image.width + x]); };
  return (1 - fv) * ((1 - fu) * at(u0, v0) + fu * at(u1, v0)) + fv * ((1 - fu) * at(u0, v1) + fu * at(u1, v1));
}

double median(std::vector<double> values) {
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

void check_inputs(const GrayImageView& color, const DepthImageView& depth, const StrapCameras& cameras,
                  const Vec3& elbow_K, const Vec3& wrist_K, const StrapDetectionOptions& o) {
  geometry::validate(cameras.depth, "cameras.depth");
  geometry::validate(cameras.color, "cameras.color");
  if (color.pixels == nullptr || color.width != cameras.color.width || color.height != cameras.color.height) {
    throw_invalid("color.pixels", "image " + std::to_string(color.width) + "x" + std::to_string(color.height) +
                                      " does not match the colour camera's " + std::to_string(cameras.color.width) +
                                      "x" + std::to_string(cameras.color.height));
  }
  if (depth.pixels == nullptr || depth.width != cameras.depth.width || depth.height != cameras.depth.height) {
    throw_invalid("depth.pixels", "image " + std::to_string(depth.width) + "x" + std::to_string(depth.height) +
                                      " does not match the depth camera's " + std::to_string(cameras.depth.width) +
                                      "x" + std::to_string(cameras.depth.height));
  }
  if (!elbow_K.allFinite()) throw_invalid("elbow_K", "not finite");
  if (!wrist_K.allFinite()) throw_invalid("wrist_K", "not finite");
  if (!cameras.color_from_depth.coeffs().allFinite() || !cameras.color_from_depth_m.allFinite()) {
    throw_invalid("cameras.color_from_depth", "not finite");
  }
  const bool fractions_ok =
      o.search_begin_fraction >= 0.0 && o.search_begin_fraction < o.search_end_fraction && o.search_end_fraction <= 1.0;
  if (o.min_samples < 4 || !(o.window_fraction > 0.0 && o.window_fraction < 0.5) || !fractions_ok ||
      !(o.match_radius_px > 0.0) || o.depth_search_radius_px < 1 || !(o.max_depth_spread_m > 0.0) ||
      o.min_depth_samples < 1 || !std::isfinite(o.min_contrast) || !std::isfinite(o.max_strap_level) ||
      !(o.side_offset_windows >= 1.0) || !std::isfinite(o.min_side_contrast)) {
    throw_invalid("options", "strap detection options out of range");
  }
}

struct ProjectedForearm {
  Vec2 elbow_px, wrist_px;
};

// The elbow and wrist in the colour image, or nullopt when either is behind the camera or outside
// the image.
std::optional<ProjectedForearm> project_forearm(const StrapCameras& cameras, const Vec3& elbow_K, const Vec3& wrist_K) {
  const Quat color_from_K = cameras.color_from_depth.normalized();
  const auto to_color = [&](const Vec3& p_K) { return Vec3(color_from_K * p_K + cameras.color_from_depth_m); };
  const auto elbow_px = geometry::project(cameras.color, to_color(elbow_K));
  const auto wrist_px = geometry::project(cameras.color, to_color(wrist_K));
  if (!elbow_px || !wrist_px || !geometry::inside_image(cameras.color, *elbow_px) ||
      !geometry::inside_image(cameras.color, *wrist_px)) {
    return std::nullopt;
  }
  return ProjectedForearm{*elbow_px, *wrist_px};
}

// Closest point of segment [a, b] to the ray origin + s * direction (s >= 0).
Vec3 closest_on_segment_to_ray(const Vec3& a, const Vec3& b, const Vec3& origin, const Vec3& direction) {
  const Vec3 d1 = b - a, d2 = direction.normalized(), r = a - origin;
  const double a11 = d1.squaredNorm(), a12 = d1.dot(d2), b1 = d1.dot(r), b2 = d2.dot(r);
  const double det = a11 - a12 * a12;  // |d2| = 1
  const double s = det > 1e-12 * a11 ? (a12 * b2 - b1) / det : 0.0;
  return a + std::clamp(s, 0.0, 1.0) * d1;
}

// Where the colour ray meets the surface the depth samples describe: a least-squares plane
// through them (PCA) when they span one, else the plane z = mean z. A depth pixel is 5-11 mm
// wide at 2 m, so this keeps the colour image's finer position along the forearm.
Vec3 surface_point_on_ray(const std::vector<Vec3>& samples, const Vec3& origin, const Vec3& direction) {
  const geometry::PointPca pca = geometry::point_pca(samples);
  // A plane needs two well-spread directions (more than ~0.1 mm); otherwise keep z = const.
  const Vec3 normal = samples.size() >= 3 && pca.variances(1) > 1e-8 ? pca.normal() : Vec3::UnitZ();
  const double denominator = normal.dot(direction);
  if (std::abs(denominator) < 0.1) return pca.centroid;  // surface seen edge-on: no stable intersection
  const Vec3 hit = origin + (normal.dot(pca.centroid - origin) / denominator) * direction;
  return (hit - pca.centroid).norm() < 0.02 ? hit : pca.centroid;
}

}  // namespace

const char* strap_miss_name(StrapMiss miss) {
  switch (miss) {
    case StrapMiss::kNone: return "none";
    case StrapMiss::kOutsideImage: return "segment outside the colour image";
    case StrapMiss::kNoDarkBand: return "no dark band along the forearm";
    case StrapMiss::kNoDepth: return "no depth reading at the band";
  }
  return "unknown";
}

StrapDetection detect_strap(const GrayImageView& color, const DepthImageView& depth, const StrapCameras& cameras,
                            const Vec3& elbow_K, const Vec3& wrist_K, const StrapDetectionOptions& options) {
  check_inputs(color, depth, cameras, elbow_K, wrist_K, options);
  StrapDetection out;
  const Quat color_from_K = cameras.color_from_depth.normalized();
  const auto to_color = [&](const Vec3& p_K) { return Vec3(color_from_K * p_K + cameras.color_from_depth_m); };
  const std::optional<ProjectedForearm> projected = project_forearm(cameras, elbow_K, wrist_K);
  if (!projected) {
    out.miss = StrapMiss::kOutsideImage;
    return out;
  }
  const Vec2& elbow_px = projected->elbow_px;
  const Vec2& wrist_px = projected->wrist_px;

  // 1. Grey profile along the projected segment.
  const double length_px = (wrist_px - elbow_px).norm();
  const int n = std::max(options.min_samples, static_cast<int>(std::ceil(length_px)) + 1);
  std::vector<double> profile(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double f = static_cast<double>(i) / (n - 1);
    profile[static_cast<std::size_t>(i)] = bilinear(color, elbow_px + f * (wrist_px - elbow_px));
  }
  // 2. Moving average (odd window, centred); darkest centre inside the search range.
  const int half = std::max(1, static_cast<int>(std::lround(options.window_fraction * (n - 1) / 2.0)));
  const int begin = std::max(half, static_cast<int>(std::ceil(options.search_begin_fraction * (n - 1))));
  const int end = std::min(n - 1 - half, static_cast<int>(std::floor(options.search_end_fraction * (n - 1))));
  if (begin > end) {
    out.miss = StrapMiss::kNoDarkBand;
    return out;
  }
  std::vector<double> prefix(profile.size() + 1, 0.0);
  for (std::size_t i = 0; i < profile.size(); ++i) prefix[i + 1] = prefix[i] + profile[i];
  int best = begin;
  double best_level = INFINITY;
  for (int i = begin; i <= end; ++i) {
    const double level =
        (prefix[static_cast<std::size_t>(i + half + 1)] - prefix[static_cast<std::size_t>(i - half)]) / (2 * half + 1);
    if (level < best_level) {
      best_level = level;
      best = i;
    }
  }
  out.fraction = static_cast<double>(best) / (n - 1);
  out.color_px = elbow_px + out.fraction * (wrist_px - elbow_px);
  out.band_level = best_level;
  out.contrast = median(profile) - best_level;
  if (out.contrast < options.min_contrast || best_level > options.max_strap_level) {
    out.miss = StrapMiss::kNoDarkBand;
    return out;
  }
  // A band, not an edge: brighter on both sides. Windows of the same length centred
  // side_offset_windows windows away from the band's centre, both inside the profile.
  const int window = 2 * half + 1;
  const int offset = static_cast<int>(std::lround(options.side_offset_windows * window));
  const auto window_level = [&](int centre) {
    return (prefix[static_cast<std::size_t>(centre + half + 1)] - prefix[static_cast<std::size_t>(centre - half)]) /
           window;
  };
  // Moved inwards where the profile ends, as long as they stay clear of the band's window.
  const int before = std::max(best - offset, half), after = std::min(best + offset, n - 1 - half);
  out.side_contrast = best - before >= window && after - best >= window
                          ? std::min(window_level(before), window_level(after)) - best_level
                          : 0.0;
  if (out.side_contrast < options.min_side_contrast) {
    out.miss = StrapMiss::kNoDarkBand;
    return out;
  }

  // 3. Colour pixel -> depth pixels -> 3D.
  const Vec3 ray_color = geometry::back_project(cameras.color, out.color_px.x(), out.color_px.y(), 1.0);
  const Quat K_from_color = color_from_K.conjugate();
  const Vec3 camera_K = K_from_color * (-cameras.color_from_depth_m);
  const Vec3 seed_K = closest_on_segment_to_ray(elbow_K, wrist_K, camera_K, K_from_color * ray_color);
  const auto seed_px = geometry::project(cameras.depth, seed_K);
  if (!seed_px) {
    out.miss = StrapMiss::kNoDepth;
    return out;
  }
  const int r = options.depth_search_radius_px;
  const int col0 = static_cast<int>(std::lround(seed_px->x())), row0 = static_cast<int>(std::lround(seed_px->y()));
  // A depth pixel covers about fx_color / fx_depth colour pixels; every point of the colour
  // image is within 0.71 of that spacing of some depth pixel, so the radius never drops below it.
  const double radius_px = std::max(options.match_radius_px, 0.75 * cameras.color.fx / cameras.depth.fx);
  // Surface samples from a neighbourhood twice the match radius: enough for a local plane.
  std::vector<Vec3> samples;
  for (int row = std::max(0, row0 - r); row <= std::min(depth.height - 1, row0 + r); ++row) {
    for (int col = std::max(0, col0 - r); col <= std::min(depth.width - 1, col0 + r); ++col) {
      const std::uint16_t mm = depth.pixels[row * depth.width + col];
      if (mm == 0) continue;
      const Vec3 p_K = geometry::back_project(cameras.depth, col, row, mm * 1e-3);
      const auto px = geometry::project(cameras.color, to_color(p_K));
      if (px && (*px - out.color_px).norm() <= 2.0 * radius_px) samples.push_back(p_K);
    }
  }
  if (!samples.empty()) {
    std::vector<double> z;
    for (const Vec3& p : samples) z.push_back(p.z());
    const double z_median = median(z);
    std::vector<Vec3> kept;
    for (const Vec3& p : samples) {
      if (std::abs(p.z() - z_median) <= options.max_depth_spread_m) kept.push_back(p);
    }
    out.depth_samples = static_cast<int>(kept.size());
    if (out.depth_samples >= options.min_depth_samples) {
      out.strap_K = surface_point_on_ray(kept, camera_K, (K_from_color * ray_color).normalized());
    }
  }
  if (out.depth_samples < options.min_depth_samples) out.miss = StrapMiss::kNoDepth;
  return out;
}

geometry::PixelRect strap_profile_rect(const StrapCameras& cameras, const Vec3& elbow_K, const Vec3& wrist_K) {
  const std::optional<ProjectedForearm> projected = project_forearm(cameras, elbow_K, wrist_K);
  if (!projected) return {};
  // bilinear() reads the pixel at a sample's floor and the next one; the profile's samples lie on
  // the segment, up to rounding.
  const Vec2 low = projected->elbow_px.cwiseMin(projected->wrist_px);
  const Vec2 high = projected->elbow_px.cwiseMax(projected->wrist_px);
  geometry::PixelRect rect;
  rect.col0 = std::max(0, static_cast<int>(std::floor(low.x())) - 1);
  rect.row0 = std::max(0, static_cast<int>(std::floor(low.y())) - 1);
  rect.col1 = std::min(cameras.color.width - 1, static_cast<int>(std::floor(high.x())) + 2);
  rect.row1 = std::min(cameras.color.height - 1, static_cast<int>(std::floor(high.y())) + 2);
  return rect;
}

}  // namespace posefuse::forearm
