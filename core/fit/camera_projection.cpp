#include "fit/camera_projection.hpp"

namespace posefuse::fit {

Projection project_with_jacobian(const raycast::DepthIntrinsics& c, const Eigen::Vector3d& p) {
  // x_n = -x/z, y_n = -y/z, L = 1 + k1 r^2 + k2 r^4 + k3 r^6, u = cx + fx L x_n, v = cy + fy L y_n.
  const double inv_z = 1.0 / p.z();
  const double xn = -p.x() * inv_z, yn = -p.y() * inv_z;
  const double r2 = xn * xn + yn * yn;
  const double radial = 1 + r2 * (c.k1 + r2 * (c.k2 + r2 * c.k3));
  const double d_radial_d_r2 = c.k1 + r2 * (2 * c.k2 + 3 * c.k3 * r2);
  Projection out;
  out.pixel = {c.cx + c.fx * radial * xn, c.cy + c.fy * radial * yn};
  Eigen::Matrix2d d_pixel_d_normalised;
  d_pixel_d_normalised << c.fx * (radial + 2 * xn * xn * d_radial_d_r2), c.fx * 2 * xn * yn * d_radial_d_r2,
      c.fy * 2 * xn * yn * d_radial_d_r2, c.fy * (radial + 2 * yn * yn * d_radial_d_r2);
  Eigen::Matrix<double, 2, 3> d_normalised_d_point;
  d_normalised_d_point << -inv_z, 0, p.x() * inv_z * inv_z, 0, -inv_z, p.y() * inv_z * inv_z;
  out.d_pixel_d_point = d_pixel_d_normalised * d_normalised_d_point;
  return out;
}

}  // namespace posefuse::fit
