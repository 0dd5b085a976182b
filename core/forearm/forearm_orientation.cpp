#include "forearm/forearm_orientation.hpp"

#include <cmath>
#include <numbers>

#include "common/error.hpp"
#include "forearm/forearm_model.hpp"
#include "geometry/rotation_matrix.hpp"

namespace posefuse::forearm {

double twist_about_y(const Quat& q) {
  // The twist is the normalised (w, 0, y, 0) part of q; its angle is 2 atan2(y, w).
  double angle = 2.0 * std::atan2(q.y(), q.w());
  if (angle > std::numbers::pi) angle -= 2.0 * std::numbers::pi;
  if (angle <= -std::numbers::pi) angle += 2.0 * std::numbers::pi;
  return angle;
}

double pronation_angle(const Quat& K_from_F_reference, const Quat& K_from_F, Side side) {
  const double twist = twist_about_y(K_from_F_reference.conjugate() * K_from_F);
  return side == Side::kRight ? -twist : twist;
}

Quat K_from_F_calibration_pose(const Vec3& shoulder_K, const Vec3& elbow_K, const Vec3& wrist_K) {
  if (!shoulder_K.allFinite()) throw_invalid("shoulder_K", "not finite");
  if (!elbow_K.allFinite()) throw_invalid("elbow_K", "not finite");
  if (!wrist_K.allFinite()) throw_invalid("wrist_K", "not finite");
  const char* field = "shoulder_K/elbow_K/wrist_K";
  const Vec3 upper = elbow_K - shoulder_K, forearm = wrist_K - elbow_K;
  if (upper.norm() < 1e-4 || forearm.norm() < 1e-4) throw_invalid(field, "two joints coincide");
  const Vec3 normal = upper.normalized().cross(forearm.normalized());
  if (normal.norm() < std::sin(20.0 * std::numbers::pi / 180.0)) {
    throw_invalid(field, "the elbow is straighter than 160 degrees: the arm's plane is undefined");
  }
  const Vec3 y = forearm.normalized();
  Vec3 x = normal.normalized();
  const double away = x.dot((0.5 * (elbow_K + wrist_K)).normalized());
  if (std::abs(away) < 0.1) throw_invalid(field, "the arm's plane contains the camera ray: the palm side is undefined");
  if (away < 0.0) x = -x;
  geometry::Mat3 K_from_F;
  K_from_F.col(0) = x;
  K_from_F.col(1) = y;
  K_from_F.col(2) = x.cross(y);
  return geometry::quat_from_rotation_matrix(K_from_F);
}

ForearmSample forearm_sample(const Quat& K_from_W, const Quat& W_from_A, const Quat& F_from_A,
                             const Quat& K_from_F_reference, Side side) {
  ForearmSample out;
  out.K_from_A = (K_from_W * W_from_A).normalized();  // eq. 11
  out.K_from_F = K_from_F_from_imu(K_from_W, W_from_A, F_from_A);
  out.pronation_rad = pronation_angle(K_from_F_reference, out.K_from_F, side);
  return out;
}

}  // namespace posefuse::forearm
