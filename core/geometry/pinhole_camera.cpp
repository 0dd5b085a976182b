#include "geometry/pinhole_camera.hpp"

#include <cmath>

#include "common/error.hpp"

namespace posefuse::geometry {

namespace {

// Distorted normalised coordinates of undistorted ones.
Vec2 distort(const PinholeCamera& c, const Vec2& n) {
  const double r2 = n.squaredNorm();
  const double radial = 1.0 + r2 * (c.k1 + r2 * (c.k2 + r2 * c.k3));
  const double x = n.x(), y = n.y();
  return {radial * x + 2.0 * c.p1 * x * y + c.p2 * (r2 + 2.0 * x * x),
          radial * y + c.p1 * (r2 + 2.0 * y * y) + 2.0 * c.p2 * x * y};
}

}  // namespace

void validate(const PinholeCamera& c, const std::string& field) {
  if (c.width <= 0 || c.height <= 0) {
    throw_invalid(field + ".width",
                  "image size " + std::to_string(c.width) + "x" + std::to_string(c.height) + " must be positive");
  }
  if (!(std::isfinite(c.fx) && c.fx > 0.0)) throw_invalid(field + ".fx", "must be a positive number");
  if (!(std::isfinite(c.fy) && c.fy > 0.0)) throw_invalid(field + ".fy", "must be a positive number");
  for (const double value : {c.cx, c.cy, c.k1, c.k2, c.k3, c.p1, c.p2}) {
    if (!std::isfinite(value)) throw_invalid(field, "principal point or distortion is not finite");
  }
}

std::optional<Vec2> project(const PinholeCamera& c, const Vec3& p) {
  if (!(p.z() > 1e-9) || !p.allFinite()) return std::nullopt;
  const Vec2 d = distort(c, Vec2(-p.x() / p.z(), -p.y() / p.z()));
  return Vec2(c.cx + c.fx * d.x(), c.cy + c.fy * d.y());
}

Vec3 back_project(const PinholeCamera& c, double u, double v, double z) {
  const double xd = (u - c.cx) / c.fx, yd = (v - c.cy) / c.fy;
  // The radial part exactly, by Newton on the radius: r L(r^2) = r_d.
  const double rd = std::hypot(xd, yd);
  double r = rd;
  for (int i = 0; i < 20; ++i) {
    const double r2 = r * r;
    const double step = (r * (1.0 + r2 * (c.k1 + r2 * (c.k2 + r2 * c.k3))) - rd) /
                        (1.0 + r2 * (3.0 * c.k1 + r2 * (5.0 * c.k2 + r2 * 7.0 * c.k3)));
    r -= step;
    if (std::abs(step) < 1e-14) break;
  }
  const double scale = rd > 0.0 ? r / rd : 1.0;
  Vec2 n(xd * scale, yd * scale);
  // The tangential part, far smaller, by fixed-point steps from there (none without it).
  for (int i = 0; i < 20 && (c.p1 != 0.0 || c.p2 != 0.0); ++i) {
    const Vec2 error = distort(c, n) - Vec2(xd, yd);
    const double r2 = n.squaredNorm();
    n -= error / (1.0 + r2 * (c.k1 + r2 * (c.k2 + r2 * c.k3)));
    if (error.squaredNorm() < 1e-28) break;
  }
  return {-n.x() * z, -n.y() * z, z};
}

bool inside_image(const PinholeCamera& c, const Vec2& uv) {
  return uv.x() >= -0.5 && uv.y() >= -0.5 && uv.x() < c.width - 0.5 && uv.y() < c.height - 0.5;
}

}  // namespace posefuse::geometry
