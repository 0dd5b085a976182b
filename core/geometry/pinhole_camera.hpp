#pragma once
// A camera image's pinhole model with Brown-Conrady distortion, in the session header's
// convention (session.proto CameraIntrinsics):
// the camera frame has x to the left, y up, z forward, so the image x axis is mirrored:
//   x_n = -x / z,  y_n = -y / z,  r2 = x_n^2 + y_n^2,  L = 1 + k1 r2 + k2 r2^2 + k3 r2^3
//   x_d = L x_n + 2 p1 x_n y_n + p2 (r2 + 2 x_n^2)
//   y_d = L y_n + p1 (r2 + 2 y_n^2) + 2 p2 x_n y_n
//   u = cx + fx x_d,  v = cy + fy y_d      (pixel centres at integer u, v)
// Used by the strap search (paper 1, II-I) to go between the RGB and depth images, and by the
// panel calibration (II-F) to back-project IR/depth pixels.
#include <optional>
#include <string>

#include <Eigen/Core>

#include "geometry/quaternion.hpp"

namespace posefuse::geometry {

using Vec2 = Eigen::Vector2d;

// The one camera model of posefuse: the session header's CameraIntrinsics, the depth camera
// of the fit's ray casting (raycast::DepthCamera), the forearm stage's strap search. Defaults:
// a typical Kinect v2 depth camera; a session header supplies each device's own.
struct PinholeCamera {
  int width = 512;                                        // pixels
  int height = 424;                                       // pixels
  double fx = 365.0, fy = 365.0, cx = 256.0, cy = 212.0;  // pixels
  double k1 = 0.09, k2 = -0.27, k3 = 0.09, p1 = 0.0, p2 = 0.0;
};

// Throws posefuse::Error kInvalidArgument `field`.<name> for non-positive sizes or focal
// lengths and non-finite values.
void validate(const PinholeCamera& camera, const std::string& field);

// Image coordinates of p (camera frame); nullopt when p is not in front of the camera.
std::optional<Vec2> project(const PinholeCamera& camera, const Vec3& p);

// The point at depth z (> 0, along the camera's z axis) that projects to (u, v): the radial
// distortion inverted by Newton on the radius, then the tangential part by fixed-point steps
// (exact to ~1e-12 for the distortions of depth and colour cameras, whose r L(r^2) increases
// over the image).
Vec3 back_project(const PinholeCamera& camera, double u, double v, double z);

// True when (u, v) lies inside the image (pixel centres 0..width-1, with half a pixel margin).
bool inside_image(const PinholeCamera& camera, const Vec2& uv);

}  // namespace posefuse::geometry
