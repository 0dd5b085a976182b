#pragma once
// A room rendered analytically for the floor's tests: planes (a floor, a back wall) seen by a
// depth camera pitched and rolled, with Kinect v2-like axial noise, and a box standing for the
// person in the body index.
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "geometry/pixel_rays.hpp"

namespace posefuse::measures::testing {

using geometry::Vec3;

inline constexpr double kDeg = std::numbers::pi / 180;

struct Plane {
  Vec3 normal_K;  // unit
  double offset_m;
};

struct Room {
  Vec3 up_K;
  std::vector<Plane> planes;
};

// A floor `height_m` below a camera pitched down by `pitch_deg` and rolled by `roll_deg`, and a
// wall 4 m ahead of it (as the camera would face it level).
inline Room room(double pitch_deg, double roll_deg, double height_m = 1.0) {
  // K_from_level: the level camera's frame turned by the pitch (about x) and roll (about z).
  const Eigen::Matrix3d K_from_level =
      (Eigen::AngleAxisd(roll_deg * kDeg, Vec3::UnitZ()) * Eigen::AngleAxisd(-pitch_deg * kDeg, Vec3::UnitX()))
          .toRotationMatrix();
  Room r;
  r.up_K = K_from_level * Vec3::UnitY();
  r.planes.push_back({r.up_K, -height_m});
  r.planes.push_back({K_from_level * Vec3::UnitZ(), 4.0});
  return r;
}

struct Frame {
  std::vector<std::uint16_t> depth_mm;
  std::vector<std::uint8_t> body_index;
};

// Nearest plane along each pixel's ray, axial noise 1.5 mm + 0.6 mm/m^2 (z - 0.4)^2, whole mm,
// 0.5-4.5 m; the central quarter of the image is a person (body index 0) at 2.5 m.
inline Frame render(const geometry::PinholeCamera& camera, const std::vector<Plane>& planes, std::uint32_t seed = 3) {
  const geometry::PixelRays rays(camera);
  const int w = camera.width, h = camera.height;
  Frame frame{std::vector<std::uint16_t>(static_cast<std::size_t>(w * h), 0),
              std::vector<std::uint8_t>(static_cast<std::size_t>(w * h), 255)};
  std::mt19937 rng(seed);
  std::normal_distribution<double> unit(0, 1);
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      const std::size_t i = static_cast<std::size_t>(row * w + col);
      const Vec3 ray = rays.point(col, row, 1.0);
      double z = INFINITY;
      if (std::abs(col - w / 2) < w / 8 && std::abs(row - h / 2) < h / 4) {
        z = 2.5;
        frame.body_index[i] = 0;
      } else {
        for (const Plane& p : planes) {
          const double along = p.normal_K.dot(ray);
          if (std::abs(along) < 1e-9) continue;
          const double t = p.offset_m / along;
          if (t > 0) z = std::min(z, t);
        }
      }
      if (!std::isfinite(z)) continue;
      z += (0.0015 + 0.0006 * (z - 0.4) * (z - 0.4)) * unit(rng);
      if (z < 0.5 || z > 4.5) continue;
      frame.depth_mm[i] = static_cast<std::uint16_t>(std::lround(z * 1000));
    }
  }
  return frame;
}

}  // namespace posefuse::measures::testing
