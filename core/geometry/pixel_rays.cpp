#include "geometry/pixel_rays.hpp"

#include "common/error.hpp"

namespace posefuse::geometry {

PixelRays::PixelRays(const PinholeCamera& camera, const std::string& field) : camera_(camera) {
  validate(camera, field);
  const long long pixels = static_cast<long long>(camera.width) * camera.height;
  if (pixels > max_pixels) {
    throw_invalid(field + ".width", "image " + std::to_string(camera.width) + "x" + std::to_string(camera.height) +
                                        " has more than " + std::to_string(max_pixels) + " pixels");
  }
  ray_xy_.resize(2 * static_cast<std::size_t>(pixels));
  std::size_t i = 0;
  for (int row = 0; row < camera.height; ++row) {
    for (int col = 0; col < camera.width; ++col) {
      // z = 1: back_project's x and y are then the ray's slopes, and z * slope is what it
      // computes for any z.
      const Vec3 ray = back_project(camera, col, row, 1.0);
      ray_xy_[i++] = ray.x();
      ray_xy_[i++] = ray.y();
    }
  }
}

}  // namespace posefuse::geometry
