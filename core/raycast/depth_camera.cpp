#include "raycast/depth_camera.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.hpp"

namespace posefuse::raycast {
namespace {

// Largest undistorted radius seen by the image (its corners), with a margin.
double max_image_radius(const DepthIntrinsics& c) {
  const double du = std::max(c.cx, c.width - c.cx) / c.fx, dv = std::max(c.cy, c.height - c.cy) / c.fy;
  return 1.2 * std::hypot(du, dv);
}

}  // namespace

void validate(const DepthIntrinsics& c) {
  if (c.width <= 0 || c.height <= 0 || c.width > 16384 || c.height > 16384)
    throw_invalid("intrinsics.size",
                  std::to_string(c.width) + "x" + std::to_string(c.height) + " is not a valid image size");
  const std::pair<const char*, double> values[] = {{"fx", c.fx}, {"fy", c.fy}, {"cx", c.cx}, {"cy", c.cy}, {"k1", c.k1},
                                                   {"k2", c.k2}, {"k3", c.k3}, {"p1", c.p1}, {"p2", c.p2}};
  for (const auto& [name, value] : values)
    if (!std::isfinite(value)) throw_invalid(std::string("intrinsics.") + name, "not finite");
  if (c.fx <= 0 || c.fy <= 0)
    throw_invalid("intrinsics.fx",
                  "focal lengths must be positive, got " + std::to_string(c.fx) + ", " + std::to_string(c.fy));
  // r * L(r^2) must increase over the image so that distortion can be inverted.
  const double r_max = max_image_radius(c);
  for (int i = 1; i <= 200; ++i) {
    const double r = r_max * i / 200.0, r2 = r * r;
    const double slope = 1 + r2 * (3 * c.k1 + r2 * (5 * c.k2 + r2 * 7 * c.k3));
    if (slope <= 0)
      throw_invalid("intrinsics.k", "radial distortion folds over at normalised radius " + std::to_string(r));
  }
}

DepthCamera::DepthCamera(const DepthIntrinsics& intrinsics) : intrinsics_(intrinsics) {
  validate(intrinsics_);
  max_undistorted_radius_ = max_image_radius(intrinsics_);
  pixel_rays_.resize(static_cast<size_t>(width()) * height());
  for (int row = 0; row < height(); ++row)
    for (int col = 0; col < width(); ++col) {
      const Eigen::Vector3d d = ray_direction(col, row);
      pixel_rays_[row * width() + col] = (d / d.z()).cast<float>();
    }
  row_y_.assign(static_cast<size_t>(height()), AxisBounds{HUGE_VALF, -HUGE_VALF});
  column_x_.assign(static_cast<size_t>(width()), AxisBounds{HUGE_VALF, -HUGE_VALF});
  for (int row = 0; row < height(); ++row)
    for (int col = 0; col < width(); ++col) {
      const Eigen::Vector3f& d = pixel_ray(col, row);
      AxisBounds& y = row_y_[static_cast<size_t>(row)];
      AxisBounds& x = column_x_[static_cast<size_t>(col)];
      y = {std::min(y.min, d.y()), std::max(y.max, d.y())};
      x = {std::min(x.min, d.x()), std::max(x.max, d.x())};
    }
  for (int col = 1; col < width(); ++col) {
    const AxisBounds &a = column_x_[static_cast<size_t>(col - 1)], &b = column_x_[static_cast<size_t>(col)];
    if (b.min > a.min || b.max > a.max) columns_fall_ = false;
  }
}

std::pair<int, int> DepthCamera::columns_within(float min_x, float max_x) const {
  if (!columns_fall_) return {0, width()};
  // Columns whose smallest x exceeds max_x come first, those whose largest x is below min_x last.
  const auto first =
      std::partition_point(column_x_.begin(), column_x_.end(), [&](const AxisBounds& x) { return x.min > max_x; });
  const auto last = std::partition_point(first, column_x_.end(), [&](const AxisBounds& x) { return x.max >= min_x; });
  return {static_cast<int>(first - column_x_.begin()), static_cast<int>(last - column_x_.begin())};
}

double DepthCamera::distort_radius(double r) const { return r * radial_factor(r * r); }

double DepthCamera::undistort_radius(double r_distorted) const {
  double r = r_distorted;
  for (int i = 0; i < 20; ++i) {
    const double r2 = r * r;
    const double f = r * radial_factor(r2) - r_distorted;
    const double slope = 1 + r2 * (3 * intrinsics_.k1 + r2 * (5 * intrinsics_.k2 + r2 * 7 * intrinsics_.k3));
    const double step = f / slope;
    r -= step;
    if (std::abs(step) < 1e-14) break;
  }
  return r;
}

Eigen::Vector3d DepthCamera::ray_direction(double u, double v) const {
  return geometry::back_project(intrinsics_, u, v, 1.0).normalized();
}

}  // namespace posefuse::raycast
