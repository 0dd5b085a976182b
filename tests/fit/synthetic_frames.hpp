#pragma once
// Depth frames rendered analytically for the fit tests: every pixel's ray (z = 1, from the
// DepthCamera) is intersected with a plane or sphere and the z stored in millimetres.
#include <Eigen/Core>
#include <functional>
#include <optional>
#include <string>

#include "common/error.hpp"

#include "fit/depth_frame.hpp"
#include "fit/zone_sampling.hpp"
#include "raycast/depth_camera.hpp"

namespace posefuse::fit::testing {

// A camera with the Kinect v2 distortion at a reduced resolution (keeps brute-force tests small).
raycast::DepthIntrinsics small_intrinsics(int width, int height);

// Frame whose depth at each pixel is depth_of_ray(ray with z = 1) in metres (nullopt: no hit and
// background); every hit pixel belongs to body 0.
DepthFrame render_frame(const raycast::DepthCamera& camera,
                        const std::function<std::optional<double>(const Eigen::Vector3d&)>& depth_of_ray);

// Plane through `point_K` with normal `normal_K`.
DepthFrame render_plane(const raycast::DepthCamera& camera, const Eigen::Vector3d& point_K,
                        const Eigen::Vector3d& normal_K);
// Sphere (front surface only).
DepthFrame render_sphere(const raycast::DepthCamera& camera, const Eigen::Vector3d& centre_K, double radius_m);

// A T-pose Kinect skeleton facing the camera at `depth_m`, and a stick-figure frame: a flat body
// at that depth whose silhouette holds the pixels near each bone (thicker for torso and head).
KinectSkeleton t_pose_skeleton(double depth_m);
DepthFrame render_stick_figure(const raycast::DepthCamera& camera, const KinectSkeleton& skeleton_K, bool with_legs);

// Field named by the posefuse::Error that f throws, or "(no error)".
template <typename F>
std::string error_field(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.field();
  }
  return "(no error)";
}

}  // namespace posefuse::fit::testing
