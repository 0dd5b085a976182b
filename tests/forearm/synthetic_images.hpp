#pragma once
// Colour and depth images of a forearm for strap-detection tests (paper 1, II-I): the forearm is
// a cylinder of radius r around the elbow -> wrist segment, skin grey except a black band
// (the strap) centred d_se from the elbow, in front of a grey wall. Rendered by exact
// ray-cylinder intersection per pixel centre, then optional Gaussian noise (inside the
// forearm's bounding box only, where the strap search looks). Optionally the upper arm too: a
// skin cylinder from the shoulder to the elbow (what the depth camera sees beside the forearm),
// and a hand: a wider skin cylinder continuing the forearm beyond the wrist (the forearm's axis
// fit runs on over it; the wrist is where it widens).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <random>
#include <vector>

#include "forearm/strap_detection.hpp"

namespace posefuse::forearm::testing {

struct ForearmScene {
  Vec3 elbow_K = Vec3(0.1, 0.25, 2.0);
  Vec3 wrist_K = Vec3(0.1, 0.51, 1.95);
  double radius_m = 0.035;        // r: forearm core to strap surface
  double strap_to_elbow_m = 0.2;  // d_se: band centre
  double strap_width_m = 0.03;
  bool strap_visible = true;  // false: skin all along (the strap never seen)
  double skin_level = 170.0, strap_level = 25.0, wall_level = 120.0;
  double wall_z_m = 3.0;
  std::optional<Vec3> shoulder_K;  // set: the upper arm is drawn, shoulder -> elbow
  double upper_arm_radius_m = 0.045;
  // > 0: the upper arm tapers, this radius at the shoulder to upper_arm_radius_m at the elbow
  // (drawn as kTaperSteps cylinders of stepped radius, like a deltoid and sleeve thinning).
  double upper_arm_shoulder_radius_m = 0.0;
  double hand_length_m = 0.0;  // > 0: the hand is drawn, wrist -> wrist + hand_length_m
  double hand_radius_m = 0.045;
  Vec3 hand_end_K() const { return wrist_K + hand_length_m * (wrist_K - elbow_K).normalized(); }
};

// Small cameras with mild distortion; the colour camera sits 5 cm to the side, turned 1 degree.
inline StrapCameras test_cameras() {
  StrapCameras c;
  c.depth = {256, 212, 183.0, 183.0, 128.0, 106.0, 0.02, -0.05, 0.0, 0.0, 0.0};
  c.color = {640, 360, 530.0, 530.0, 320.0, 180.0, 0.03, -0.04, 0.0, 0.001, -0.0005};
  c.color_from_depth = Quat(Eigen::AngleAxisd(1.0 * EIGEN_PI / 180.0, Vec3::UnitY()));
  c.color_from_depth_m = Vec3(-0.052, 0.0, 0.0);
  return c;
}

// Nearest hit of the ray origin + t dir (t > 0) with the finite cylinder of radius `radius_m`
// around a -> b; axial position from a out.
inline std::optional<double> hit_cylinder(const Vec3& a, const Vec3& b, double radius_m, const Vec3& origin,
                                          const Vec3& dir, double* axial_m) {
  const Vec3 axis = (b - a).normalized();
  const double length = (b - a).norm();
  const Vec3 w = origin - a;
  const Vec3 v_perp = dir - dir.dot(axis) * axis, w_perp = w - w.dot(axis) * axis;
  const double qa = v_perp.squaredNorm(), qb = 2.0 * w_perp.dot(v_perp),
               qc = w_perp.squaredNorm() - radius_m * radius_m;
  const double disc = qb * qb - 4.0 * qa * qc;
  if (qa < 1e-12 || disc < 0.0) return std::nullopt;
  const double t = (-qb - std::sqrt(disc)) / (2.0 * qa);
  const double along = (w + t * dir).dot(axis);
  if (t <= 0.0 || along < 0.0 || along > length) return std::nullopt;
  *axial_m = along;
  return t;
}

// The forearm's hit (axial position from the elbow out), or the upper arm's when it is drawn
// and nearer (axial set to -1: never on the strap).
inline std::optional<double> hit_cylinder(const ForearmScene& s, const Vec3& origin, const Vec3& dir, double* axial_m) {
  std::optional<double> t = hit_cylinder(s.elbow_K, s.wrist_K, s.radius_m, origin, dir, axial_m);
  if (s.hand_length_m > 0.0) {
    double hand_axial = 0.0;
    const auto hand = hit_cylinder(s.wrist_K, s.hand_end_K(), s.hand_radius_m, origin, dir, &hand_axial);
    if (hand && (!t || *hand < *t)) {
      t = hand;
      *axial_m = (s.wrist_K - s.elbow_K).norm() + hand_axial;
    }
  }
  if (s.shoulder_K) {
    constexpr int kTaperSteps = 30;
    const int steps = s.upper_arm_shoulder_radius_m > 0.0 ? kTaperSteps : 1;
    for (int i = 0; i < steps; ++i) {
      const double f0 = static_cast<double>(i) / steps, f1 = static_cast<double>(i + 1) / steps;
      const double radius_m = steps == 1
                                  ? s.upper_arm_radius_m
                                  : s.upper_arm_shoulder_radius_m +
                                        (0.5 * (f0 + f1)) * (s.upper_arm_radius_m - s.upper_arm_shoulder_radius_m);
      double upper_axial = 0.0;
      const auto upper =
          hit_cylinder(*s.shoulder_K + f0 * (s.elbow_K - *s.shoulder_K),
                       *s.shoulder_K + f1 * (s.elbow_K - *s.shoulder_K), radius_m, origin, dir, &upper_axial);
      if (upper && (!t || *upper < *t)) {
        t = upper;
        *axial_m = -1.0;
      }
    }
  }
  return t;
}

struct ForearmImages {
  std::vector<std::uint8_t> gray;
  std::vector<std::uint16_t> depth_mm;
  GrayImageView gray_view(const StrapCameras& c) const { return {c.color.width, c.color.height, gray.data()}; }
  DepthImageView depth_view(const StrapCameras& c) const { return {c.depth.width, c.depth.height, depth_mm.data()}; }
};

// Pixels [col0, col1] x [row0, row1] that can see the cylinder: the projected end circles'
// bounding box with a margin (rays elsewhere only see the wall).
struct PixelBox {
  int col0, col1, row0, row1;
  bool contains(int col, int row) const { return col >= col0 && col <= col1 && row >= row0 && row <= row1; }
};
inline PixelBox cylinder_box(const ForearmScene& s, const PinholeCamera& camera, const Quat& cam_from_K,
                             const Vec3& cam_from_K_m) {
  PixelBox box{camera.width, -1, camera.height, -1};
  std::vector<Vec3> ends = {s.elbow_K, s.wrist_K};
  if (s.shoulder_K) ends.push_back(*s.shoulder_K);
  if (s.hand_length_m > 0.0) ends.push_back(s.hand_end_K());
  const double radius_m =
      std::max({s.radius_m, s.shoulder_K ? s.upper_arm_radius_m : 0.0,
                s.shoulder_K ? s.upper_arm_shoulder_radius_m : 0.0, s.hand_length_m > 0.0 ? s.hand_radius_m : 0.0});
  for (const Vec3& end : ends) {
    const Vec3 p = cam_from_K * end + cam_from_K_m;
    const auto uv = geometry::project(camera, p);
    if (!uv) return {0, camera.width - 1, 0, camera.height - 1};
    const int margin = 4 + static_cast<int>(std::ceil(1.5 * camera.fx * radius_m / p.z()));
    box.col0 = std::min(box.col0, static_cast<int>(uv->x()) - margin);
    box.col1 = std::max(box.col1, static_cast<int>(uv->x()) + margin);
    box.row0 = std::min(box.row0, static_cast<int>(uv->y()) - margin);
    box.row1 = std::max(box.row1, static_cast<int>(uv->y()) + margin);
  }
  return box;
}

inline ForearmImages render_forearm(const ForearmScene& s, const StrapCameras& c, double gray_noise = 0.0,
                                    double depth_noise_m = 0.0, std::uint64_t seed = 1) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  ForearmImages out;
  out.gray.resize(static_cast<std::size_t>(c.color.width * c.color.height));
  const Quat K_from_color = c.color_from_depth.conjugate();
  const Vec3 color_origin_K = K_from_color * (-c.color_from_depth_m);
  const PixelBox color_box = cylinder_box(s, c.color, c.color_from_depth, c.color_from_depth_m);
  for (int row = 0; row < c.color.height; ++row) {
    for (int col = 0; col < c.color.width; ++col) {
      double axial = 0.0, level = s.wall_level;
      if (color_box.contains(col, row) &&
          hit_cylinder(s, color_origin_K, K_from_color * geometry::back_project(c.color, col, row, 1.0), &axial)) {
        const bool on_strap = s.strap_visible && std::abs(axial - s.strap_to_elbow_m) <= s.strap_width_m / 2;
        level = on_strap ? s.strap_level : s.skin_level;
      }
      if (color_box.contains(col, row)) level += gray_noise * normal(rng);  // only where it matters: fast
      out.gray[static_cast<std::size_t>(row * c.color.width + col)] =
          static_cast<std::uint8_t>(std::clamp(std::lround(level), 0L, 255L));
    }
  }
  out.depth_mm.resize(static_cast<std::size_t>(c.depth.width * c.depth.height));
  const PixelBox depth_box = cylinder_box(s, c.depth, Quat::Identity(), Vec3::Zero());
  for (int row = 0; row < c.depth.height; ++row) {
    for (int col = 0; col < c.depth.width; ++col) {
      double axial = 0.0;
      std::optional<double> t;  // along a z = 1 ray: the depth itself
      if (depth_box.contains(col, row))
        t = hit_cylinder(s, Vec3::Zero(), geometry::back_project(c.depth, col, row, 1.0), &axial);
      const double z = (t ? *t : s.wall_z_m) + (depth_box.contains(col, row) ? depth_noise_m * normal(rng) : 0.0);
      out.depth_mm[static_cast<std::size_t>(row * c.depth.width + col)] =
          static_cast<std::uint16_t>(std::lround(z * 1000.0));
    }
  }
  return out;
}

}  // namespace posefuse::forearm::testing
