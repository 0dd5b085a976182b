#pragma once
// Every pixel's viewing ray of one camera, undistorted once. The forearm stage's depth searches
// back-project thousands of depth pixels per arm and frame, and back_project inverts the
// distortion by Newton steps each time; the inversion depends on the pixel only, so a table
// built when the session's camera is known turns each back-projection into three products.
#include <vector>

#include "geometry/pinhole_camera.hpp"

namespace posefuse::geometry {

class PixelRays {
 public:
  // Throws posefuse::Error kInvalidArgument `field`.<name> for a camera that validate() refuses
  // or whose table would exceed max_pixels (a table holds 16 bytes per pixel).
  explicit PixelRays(const PinholeCamera& camera, const std::string& field = "camera");

  static constexpr long long max_pixels = 16LL * 1024 * 1024;

  const PinholeCamera& camera() const { return camera_; }

  // back_project(camera(), col, row, z), bit for bit: the ray is stored as (x / z, y / z) of the
  // pixel centre (col, row), which must lie inside the image.
  Vec3 point(int col, int row, double z) const {
    const double* ray = &ray_xy_[2 * (static_cast<std::size_t>(row) * static_cast<std::size_t>(camera_.width) +
                                      static_cast<std::size_t>(col))];
    return {ray[0] * z, ray[1] * z, z};
  }

 private:
  PinholeCamera camera_;
  std::vector<double> ray_xy_;  // row-major, two per pixel
};

}  // namespace posefuse::geometry
