#pragma once
// Is this frame's visual forearm usable? (paper 1, II-J). Pure functions of one frame.
#include <numbers>

#include "forearm/forearm_types.hpp"

namespace posefuse::forearm {

struct OcclusionTestOptions {
  double max_direction_angle_rad = std::numbers::pi / 6.0;  // II-J.1: 30 degrees
  // II-J.1 rejects a forearm "nearly parallel to the camera ray" without a number; we reject
  // when the forearm axis is within this angle of the ray to its midpoint.
  double min_ray_angle_rad = std::numbers::pi / 9.0;  // 20 degrees
  double max_strap_distance_m = 0.05;  // II-J.2
};

// Angle between the visual elbow->wrist direction and the IMU's rot(K_from_F, [0, 1, 0]).
double forearm_direction_angle(const Vec3& elbow_K, const Vec3& wrist_K, const Quat& K_from_F);

// Angle in [0, pi/2] between the forearm axis and the camera ray (from K's origin) to its midpoint.
double camera_ray_angle(const Vec3& elbow_K, const Vec3& wrist_K);

// Strap against the elbow->wrist segment: distance to the segment, and where along it the strap
// projects (0 at the elbow, 1 at the wrist, unclamped).
struct StrapOnSegment {
  double distance_m = 0.0;
  double fraction = 0.0;
};
StrapOnSegment strap_on_segment(const Vec3& strap_K, const Vec3& elbow_K, const Vec3& wrist_K);

enum class VisualRejection {
  kNone,
  kDegenerate,          // non-finite input or elbow == wrist
  kDirectionDisagrees,  // II-J.1: more than 30 degrees from the IMU's forearm axis
  kGrazingView,         // II-J.1: forearm nearly along the camera ray
  kStrapOffSegment,     // II-J.2: strap more than 5 cm from the segment
  kStrapNearerElbow,    // II-J.2: strap must be nearer the wrist
};
const char* visual_rejection_name(VisualRejection r);

struct VisualCheck {
  VisualRejection rejection = VisualRejection::kNone;
  double direction_angle_rad = 0.0;
  double ray_angle_rad = 0.0;
  StrapOnSegment strap;
  bool accepted() const { return rejection == VisualRejection::kNone; }
};

// All of II-J in order; the first failing test names the rejection. Never throws: a frame that
// cannot be tested is rejected as kDegenerate.
VisualCheck check_visual_forearm(const Vec3& elbow_K, const Vec3& wrist_K, const Vec3& strap_K,
                                 const Quat& K_from_F, const OcclusionTestOptions& options = {});

}  // namespace posefuse::forearm
