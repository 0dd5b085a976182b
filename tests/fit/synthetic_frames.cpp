#include "synthetic_frames.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace posefuse::fit::testing {

raycast::DepthIntrinsics small_intrinsics(int width, int height) {
  raycast::DepthIntrinsics c;
  const double scale = static_cast<double>(width) / c.width;
  c.width = width;
  c.height = height;
  c.fx *= scale;
  c.fy *= scale;
  c.cx = width / 2.0;
  c.cy = height / 2.0;
  return c;
}

DepthFrame render_frame(const raycast::DepthCamera& camera,
                        const std::function<std::optional<double>(const Eigen::Vector3d&)>& depth_of_ray) {
  DepthFrame frame;
  frame.width = camera.width();
  frame.height = camera.height();
  frame.depth_mm.assign(static_cast<size_t>(frame.width) * frame.height, kNoDepth);
  frame.body_index.assign(frame.depth_mm.size(), kNoBody);
  for (int row = 0; row < frame.height; ++row)
    for (int col = 0; col < frame.width; ++col) {
      const auto z = depth_of_ray(camera.pixel_ray(col, row).cast<double>());
      if (!z || *z <= 0 || *z > 60.0) continue;
      const size_t i = static_cast<size_t>(row) * frame.width + col;
      frame.depth_mm[i] = static_cast<uint16_t>(std::lround(*z * 1000));
      frame.body_index[i] = 0;
    }
  return frame;
}

DepthFrame render_plane(const raycast::DepthCamera& camera, const Eigen::Vector3d& point_K,
                        const Eigen::Vector3d& normal_K) {
  return render_frame(camera, [&](const Eigen::Vector3d& ray) -> std::optional<double> {
    const double denom = normal_K.dot(ray);
    if (std::abs(denom) < 1e-9) return std::nullopt;
    return normal_K.dot(point_K) / denom;  // t along a z = 1 ray is the depth
  });
}

DepthFrame render_sphere(const raycast::DepthCamera& camera, const Eigen::Vector3d& centre_K, double radius_m) {
  return render_frame(camera, [&](const Eigen::Vector3d& ray) -> std::optional<double> {
    // |t ray - c|^2 = R^2, nearest root.
    const double a = ray.squaredNorm(), b = -2 * ray.dot(centre_K), c = centre_K.squaredNorm() - radius_m * radius_m;
    const double disc = b * b - 4 * a * c;
    if (disc < 0) return std::nullopt;
    return (-b - std::sqrt(disc)) / (2 * a);
  });
}

KinectSkeleton t_pose_skeleton(double depth_m) {
  // x is to the camera's left; the subject faces the camera, so its left side has x < 0.
  auto at = [&](double x, double y) { return Eigen::Vector3d(x, y, depth_m); };
  KinectSkeleton s;
  s[0] = at(0, -0.1);     // SpineBase
  s[1] = at(0, 0.15);     // SpineMid
  s[2] = at(0, 0.45);     // Neck
  s[3] = at(0, 0.6);      // Head
  s[4] = at(-0.18, 0.4);  // ShoulderLeft
  s[5] = at(-0.45, 0.4);  // ElbowLeft
  s[6] = at(-0.7, 0.4);   // WristLeft
  s[7] = at(-0.78, 0.4);  // HandLeft
  s[8] = at(0.18, 0.4);   // ShoulderRight
  s[9] = at(0.45, 0.4);
  s[10] = at(0.7, 0.4);
  s[11] = at(0.78, 0.4);
  s[12] = at(-0.1, -0.15);  // HipLeft
  s[13] = at(-0.1, -0.55);
  s[14] = at(-0.1, -0.9);
  s[15] = at(-0.1, -0.95);
  s[16] = at(0.1, -0.15);  // HipRight
  s[17] = at(0.1, -0.55);
  s[18] = at(0.1, -0.9);
  s[19] = at(0.1, -0.95);
  s[20] = at(0, 0.4);      // SpineShoulder
  s[21] = at(-0.85, 0.4);  // HandTipLeft
  s[22] = at(-0.8, 0.43);  // ThumbLeft
  s[23] = at(0.85, 0.4);
  s[24] = at(0.8, 0.43);
  return s;
}

namespace {
double segment_distance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (a + t * ab - p).norm();
}
}  // namespace

DepthFrame render_stick_figure(const raycast::DepthCamera& camera, const KinectSkeleton& s, bool with_legs) {
  struct Limb {
    int from, to;
    double half_width_m;
  };
  std::vector<Limb> limbs = {{0, 20, 0.15}, {20, 3, 0.08}, {4, 6, 0.05}, {6, 21, 0.05}, {8, 10, 0.05}, {10, 23, 0.05}};
  if (with_legs) limbs.insert(limbs.end(), {{12, 15, 0.07}, {16, 19, 0.07}});
  const double depth_m = s[0].z();
  return render_frame(camera, [&](const Eigen::Vector3d& ray) -> std::optional<double> {
    const Eigen::Vector2d p = (ray * depth_m).head<2>();
    for (const Limb& limb : limbs)
      if (segment_distance(p, s[limb.from].head<2>(), s[limb.to].head<2>()) <= limb.half_width_m) return depth_m;
    return std::nullopt;
  });
}

}  // namespace posefuse::fit::testing
