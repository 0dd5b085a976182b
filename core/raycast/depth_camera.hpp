#pragma once
// Depth camera model for ray casting: pinhole intrinsics with Brown-Conrady distortion (radial
// k1 k2 k3, tangential p1 p2), as the Kinect v2 depth camera and its SDK use, with a table of
// pixel rays.
//
// Conventions (paper 1, II-B): the camera frame K has x to the left, y up and z forward (the
// viewing direction). Pixel (col, row) has its centre at image coordinates (u, v) = (col, row),
// u growing to the right and v growing downwards in the image, as OpenCV. Therefore
//   x_n = -x / z,  y_n = -y / z                  (normalised, image-aligned: right, down)
//   L   = 1 + k1 r^2 + k2 r^4 + k3 r^6,  r^2 = x_n^2 + y_n^2
//   x_d = L x_n + 2 p1 x_n y_n + p2 (r^2 + 2 x_n^2),  y_d = L y_n + p1 (r^2 + 2 y_n^2) + 2 p2 x_n y_n
//   u   = cx + fx * x_d,  v = cy + fy * y_d
// A point to the camera's left (x > 0) lands left of the centre column (u < cx); a point above
// the optical axis (y > 0) lands above the centre row (v < cy). Depth images store z (not the
// ray length) in millimetres, 0 where nothing was seen.
#include <Eigen/Core>
#include <optional>
#include <utility>
#include <vector>

#include "geometry/pinhole_camera.hpp"

namespace posefuse::raycast {

// The depth camera's intrinsics are the one camera model (geometry/pinhole_camera.hpp), with
// its tangential distortion p1, p2.
using DepthIntrinsics = geometry::PinholeCamera;

// Throws posefuse::Error for non-positive sizes or focal lengths, non-finite values, or a
// distortion that is not monotonic over the image (cannot be inverted).
void validate(const DepthIntrinsics& intrinsics);

class DepthCamera {
 public:
  explicit DepthCamera(const DepthIntrinsics& intrinsics);

  const DepthIntrinsics& intrinsics() const { return intrinsics_; }
  int width() const { return intrinsics_.width; }
  int height() const { return intrinsics_.height; }

  // Image coordinates of a point in K; nullopt when it is not in front of the camera or lies
  // far outside the field of view (beyond 1.2 x the image corner's radius, where the distortion
  // polynomial is not validated and may fold back into the image).
  // Inline: D_3D (fit/behind_surface_map) classifies voxels by projecting them, millions per frame.
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& p_K) const {
    if (!(p_K.z() > 0) || !p_K.allFinite()) return std::nullopt;
    const double xn = -p_K.x() / p_K.z(), yn = -p_K.y() / p_K.z();
    // Beyond the validated field the polynomial may fold back into the image.
    if (xn * xn + yn * yn > max_undistorted_radius_ * max_undistorted_radius_) return std::nullopt;
    const double r2 = xn * xn + yn * yn, l = radial_factor(r2);
    const double p1 = intrinsics_.p1, p2 = intrinsics_.p2;
    const double xd = l * xn + 2 * p1 * xn * yn + p2 * (r2 + 2 * xn * xn);
    const double yd = l * yn + p1 * (r2 + 2 * yn * yn) + 2 * p2 * xn * yn;
    return Eigen::Vector2d(intrinsics_.cx + intrinsics_.fx * xd, intrinsics_.cy + intrinsics_.fy * yd);
  }
  // Unit ray direction in K through image coordinates (u, v) (inverse of project).
  Eigen::Vector3d ray_direction(double u, double v) const;
  // Direction in K with z = 1 through the centre of pixel (col, row), from a table.
  const Eigen::Vector3f& pixel_ray(int col, int row) const { return pixel_rays_[row * width() + col]; }

  // For renderers that skip what a bounding box of rays cannot reach (exact: pixels inside
  // still need their own test). Columns [first, second) outside which no pixel ray of any row
  // has x in [min_x, max_x] (from each column's ray bounds; x falls with the column), and
  // whether some ray of `row` has y in [min_y, max_y].
  std::pair<int, int> columns_within(float min_x, float max_x) const;
  bool row_within(int row, float min_y, float max_y) const {
    const AxisBounds& b = row_y_[static_cast<size_t>(row)];
    return b.max >= min_y && b.min <= max_y;
  }

  // L(r^2) = 1 + k1 r^2 + k2 r^4 + k3 r^6.
  double radial_factor(double r2) const {
    return 1 + r2 * (intrinsics_.k1 + r2 * (intrinsics_.k2 + r2 * intrinsics_.k3));
  }
  // Radial distortion: distorted radius for an undistorted one, and its inverse (Newton).
  double distort_radius(double r) const;
  double undistort_radius(double r_distorted) const;

 private:
  DepthIntrinsics intrinsics_;
  std::vector<Eigen::Vector3f> pixel_rays_;  // z = 1 rays per pixel
  struct AxisBounds {
    float min, max;
  };
  std::vector<AxisBounds> row_y_;     // per row, the range of its rays' y
  std::vector<AxisBounds> column_x_;  // per column, the range of its rays' x
  bool columns_fall_ = true;          // both bounds of column_x_ never increase with the column
  double max_undistorted_radius_ = 0;
};

}  // namespace posefuse::raycast
