#pragma once
// Is this frame's visual forearm usable? (paper 1, II-J). Pure functions of one frame.
#include <cstdint>
#include <numbers>

#include "forearm/forearm_types.hpp"

namespace posefuse::forearm {

struct OcclusionTestOptions {
  double max_direction_angle_rad = std::numbers::pi / 6.0;  // II-J.1: 30 degrees
  // II-J.1 rejects a forearm "nearly parallel to the camera ray" without a number; we reject
  // when the forearm axis is within this angle of the ray to its midpoint.
  double min_ray_angle_rad = std::numbers::pi / 9.0;  // 20 degrees
  double max_strap_distance_m = 0.05;                 // II-J.2
  // Beyond the paper (check_strap_against_elbow): the SDK elbow's bias (5-10 cm) plus 3 cm.
  double max_elbow_disagreement_m = 0.13;
  // Beyond the paper (check_strap_continuity): how far the elbow a strap implies may move from the
  // one the last visible frame implied, max_elbow_jump_m + max_elbow_speed_m_s * dt, tested while
  // that frame is at most max_continuity_gap_s old.
  double max_elbow_jump_m = 0.04;
  double max_elbow_speed_m_s = 2.0;
  double max_continuity_gap_s = 0.1;
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
  kStrapFarFromElbow,   // beyond the paper: eq. 10 from the strap far from eq. 10 from the SDK elbow
  kStrapJumped,         // beyond the paper: the elbow the strap implies jumped since the last visible frame
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
VisualCheck check_visual_forearm(const Vec3& elbow_K, const Vec3& wrist_K, const Vec3& strap_K, const Quat& K_from_F,
                                 const OcclusionTestOptions& options = {});

// Beyond the paper: the IMU position from the strap (eq. 10) against the one from the SDK's elbow
// carried along the IMU's forearm axis (live_gap.hpp imu_position_from_elbow). II-J tests the
// strap against the segment it was searched on, so a dark band found on another body part far
// along a segment that itself runs on past the hand passes them: on the body render the other
// arm's strap with the hands together in front of the belly, and a dark band near a hanging
// arm's hand (seeds 2 and 3: 12-24 cm from the truth, 14-27 cm from the elbow's estimate; one at
// 10 cm from the truth, 8 cm from the elbow's estimate, passes). Good straps lie within
// 10-11 cm of the elbow's estimate (p99 on the same sessions; its median, 8 cm, is the SDK
// elbow's bias). kStrapFarFromElbow beyond options.max_elbow_disagreement_m, kDegenerate for
// non-finite input, else kNone.
VisualRejection check_strap_against_elbow(const Vec3& imu_from_strap_K, const Vec3& imu_from_elbow_K,
                                          const OcclusionTestOptions& options = {});

// Beyond the paper: the elbow each accepted strap implies (eq. 10's IMU position less the IMU's
// offset from the elbow, turned by that frame's K_from_F: implied_elbow) moves like an elbow
// between two nearby frames. A dark band found somewhere else for one frame (on the body render:
// 16-18 cm towards the elbow on a straightening arm whose segment runs up the upper arm) makes it
// jump. kStrapJumped when the previous visible frame is at most options.max_continuity_gap_s
// before this one and the implied elbows lie more than max_elbow_jump_m + max_elbow_speed_m_s * dt
// apart; kNone when it is older (nothing to compare with) or within; kDegenerate for non-finite
// input or a time not after the previous one.
VisualRejection check_strap_continuity(const Vec3& implied_elbow_K, std::int64_t t_us,
                                       const Vec3& previous_implied_elbow_K, std::int64_t previous_t_us,
                                       const OcclusionTestOptions& options = {});

}  // namespace posefuse::forearm
