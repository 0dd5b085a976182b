#include "forearm/occlusion_tests.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace posefuse::forearm {

namespace {
double angle_between_vectors(const Vec3& a, const Vec3& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }
}  // namespace

double forearm_direction_angle(const Vec3& elbow_K, const Vec3& wrist_K, const Quat& K_from_F) {
  return angle_between_vectors(wrist_K - elbow_K, K_from_F * Vec3::UnitY());
}

double camera_ray_angle(const Vec3& elbow_K, const Vec3& wrist_K) {
  const double a = angle_between_vectors(wrist_K - elbow_K, 0.5 * (elbow_K + wrist_K));
  return std::min(a, std::numbers::pi - a);
}

StrapOnSegment strap_on_segment(const Vec3& strap_K, const Vec3& elbow_K, const Vec3& wrist_K) {
  const Vec3 axis = wrist_K - elbow_K;
  StrapOnSegment s;
  s.fraction = (strap_K - elbow_K).dot(axis) / axis.squaredNorm();
  const Vec3 nearest = elbow_K + std::clamp(s.fraction, 0.0, 1.0) * axis;
  s.distance_m = (strap_K - nearest).norm();
  return s;
}

const char* visual_rejection_name(VisualRejection r) {
  switch (r) {
    case VisualRejection::kNone: return "accepted";
    case VisualRejection::kDegenerate: return "degenerate";
    case VisualRejection::kDirectionDisagrees: return "direction disagrees with the IMU";
    case VisualRejection::kGrazingView: return "forearm along the camera ray";
    case VisualRejection::kStrapOffSegment: return "strap off the elbow-wrist segment";
    case VisualRejection::kStrapNearerElbow: return "strap nearer the elbow";
    case VisualRejection::kStrapFarFromElbow: return "strap far from the SDK elbow's estimate";
    case VisualRejection::kStrapJumped: return "strap's elbow jumped since the last visible frame";
  }
  return "unknown";
}

VisualCheck check_visual_forearm(const Vec3& elbow_K, const Vec3& wrist_K, const Vec3& strap_K, const Quat& K_from_F,
                                 const OcclusionTestOptions& o) {
  VisualCheck c;
  if (!elbow_K.allFinite() || !wrist_K.allFinite() || !strap_K.allFinite() || !K_from_F.coeffs().allFinite() ||
      (wrist_K - elbow_K).norm() < 1e-4 || (elbow_K + wrist_K).norm() < 1e-4) {
    c.rejection = VisualRejection::kDegenerate;
    return c;
  }
  c.direction_angle_rad = forearm_direction_angle(elbow_K, wrist_K, K_from_F.normalized());
  c.ray_angle_rad = camera_ray_angle(elbow_K, wrist_K);
  c.strap = strap_on_segment(strap_K, elbow_K, wrist_K);
  if (c.direction_angle_rad > o.max_direction_angle_rad) {
    c.rejection = VisualRejection::kDirectionDisagrees;
  } else if (c.ray_angle_rad < o.min_ray_angle_rad) {
    c.rejection = VisualRejection::kGrazingView;
  } else if (c.strap.distance_m > o.max_strap_distance_m) {
    c.rejection = VisualRejection::kStrapOffSegment;
  } else if (c.strap.fraction <= 0.5) {
    c.rejection = VisualRejection::kStrapNearerElbow;
  }
  return c;
}

VisualRejection check_strap_against_elbow(const Vec3& imu_from_strap_K, const Vec3& imu_from_elbow_K,
                                          const OcclusionTestOptions& o) {
  if (!imu_from_strap_K.allFinite() || !imu_from_elbow_K.allFinite()) return VisualRejection::kDegenerate;
  return (imu_from_strap_K - imu_from_elbow_K).norm() > o.max_elbow_disagreement_m ? VisualRejection::kStrapFarFromElbow
                                                                                   : VisualRejection::kNone;
}

VisualRejection check_strap_continuity(const Vec3& implied_elbow_K, std::int64_t t_us,
                                       const Vec3& previous_implied_elbow_K, std::int64_t previous_t_us,
                                       const OcclusionTestOptions& o) {
  if (!implied_elbow_K.allFinite() || !previous_implied_elbow_K.allFinite() || t_us <= previous_t_us)
    return VisualRejection::kDegenerate;
  const double dt_s = 1e-6 * static_cast<double>(t_us - previous_t_us);
  if (dt_s > o.max_continuity_gap_s) return VisualRejection::kNone;
  return (implied_elbow_K - previous_implied_elbow_K).norm() > o.max_elbow_jump_m + o.max_elbow_speed_m_s * dt_s
             ? VisualRejection::kStrapJumped
             : VisualRejection::kNone;
}

}  // namespace posefuse::forearm
