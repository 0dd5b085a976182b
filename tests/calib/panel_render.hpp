#pragma once
// The calibration panel rendered into a depth camera's IR and depth images (paper 1, Fig. 1b):
// the board a dull IR grey with depth, the marker spheres saturated in IR with no depth (too
// reflective for time of flight), a far wall behind. Exact ray casting per pixel centre, then
// optional Gaussian noise. Optionally stepped (the half of the board beyond the middle of the
// long leg raised by step_m: a warped or badly assembled panel) to test the flatness check.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "calib/panel_in_camera.hpp"

namespace posefuse::calib::testing {

inline PinholeCamera kinect_depth_camera() {
  return {512, 424, 365.0, 365.0, 256.0, 212.0, 0.09, -0.27, 0.09, 0.0, 0.0};
}

struct PanelImages {
  std::vector<std::uint16_t> ir, depth_mm;
  IrImageView ir_view(const PinholeCamera& c) const { return {c.width, c.height, ir.data()}; }
  DepthView depth_view(const PinholeCamera& c) const { return {c.width, c.height, depth_mm.data()}; }
};

struct PanelRenderOptions {
  double depth_noise_m = 0.0;
  double ir_noise = 0.0;
  double step_m = 0.0;          // board surface z_P offset for x_P > long_leg / 2
  bool cover_marker_3 = false;  // M3 covered: only three bright points
  std::uint64_t seed = 1;
};

inline PanelImages render_panel(const PanelGeometry& panel, const PanelPose& K_pose, const PinholeCamera& camera,
                                const PanelRenderOptions& o = {}) {
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  PanelImages out;
  const std::size_t n = static_cast<std::size_t>(camera.width * camera.height);
  out.ir.assign(n, 1500);
  out.depth_mm.assign(n, 3500);
  const Quat P_from_K = K_pose.X_from_P.conjugate();
  const std::array<Vec3, 4> markers = panel.markers_P();
  for (int row = 0; row < camera.height; ++row) {
    for (int col = 0; col < camera.width; ++col) {
      const Vec3 ray_K = geometry::back_project(camera, col, row, 1.0);  // z = 1: t is the depth
      const Vec3 origin_P = P_from_K * (-K_pose.origin_X), dir_P = P_from_K * ray_K;
      const std::size_t i = static_cast<std::size_t>(row * camera.width + col);
      // Markers first (they stand in front of the board).
      bool marker = false;
      for (std::size_t m = 0; m < markers.size(); ++m) {
        if (m == 3 && o.cover_marker_3) continue;
        const Vec3 w = origin_P - markers[m];
        const double a = dir_P.squaredNorm(), b = 2 * w.dot(dir_P),
                     c = w.squaredNorm() - std::pow(panel.marker_radius_m, 2);
        if (b * b - 4 * a * c >= 0) marker = true;
      }
      if (marker) {
        out.ir[i] = 60000;
        out.depth_mm[i] = 0;
        continue;
      }
      if (std::abs(dir_P.z()) < 1e-9) continue;
      double t = -origin_P.z() / dir_P.z();
      Vec3 hit = origin_P + t * dir_P;
      if (o.step_m != 0.0) {
        const double t_step = (o.step_m - origin_P.z()) / dir_P.z();
        const Vec3 hit_step = origin_P + t_step * dir_P;
        if (hit_step.x() > panel.long_leg_m / 2) {
          t = t_step;
          hit = hit_step;
        }
      }
      if (t <= 0 || hit.x() < panel.board_x_min_m || hit.x() > panel.board_x_max_m || hit.y() < panel.board_y_min_m ||
          hit.y() > panel.board_y_max_m) {
        continue;
      }
      out.ir[i] = static_cast<std::uint16_t>(std::clamp(8000.0 + o.ir_noise * normal(rng), 0.0, 65535.0));
      out.depth_mm[i] = static_cast<std::uint16_t>(std::lround(1000.0 * (t + o.depth_noise_m * normal(rng))));
    }
  }
  return out;
}

}  // namespace posefuse::calib::testing
