#pragma once
// Inputs shared by the forearm stage: the rigid forearm model (paper 1, II-H) and the time
// series it works on, all on the camera clock (after core/sync) and in camera frame K.
#include <cstdint>
#include <vector>

#include "geometry/quaternion.hpp"

namespace posefuse::forearm {

using geometry::Quat;
using geometry::Vec3;

inline constexpr double kGravity = 9.81;  // m/s^2, as in eq. 12

// Rigid forearm (II-H, Fig. 2). In F the elbow is at (0, -d_se, 0), the wrist at (0, d_sw, 0)
// and the arm IMU at (r, 0, 0); the shoulder is d_ul from the elbow.
struct ForearmModel {
  double r_m = 0.0;                  // forearm core to strap surface
  double d_se_m = 0.0;               // strap to elbow
  double d_sw_m = 0.0;               // strap to wrist
  double d_ul_m = 0.0;               // shoulder to elbow (upper arm length)
  Quat F_from_A = Quat::Identity();  // paper's ^A_F q (eq. 9)
};

// One depth-frame estimate of the arm IMU position (eq. 10) and whether it passed the
// occlusion tests of II-J. Occluded samples' positions are ignored (may be NaN).
struct TrackSample {
  std::int64_t t_us = 0;
  Vec3 p_K = Vec3::Zero();
  bool visible = false;
};

// One arm IMU sample: orientation from the filter mapped to K (eq. 11) and the measured
// specific force in A (reads +g upwards at rest).
struct ArmSample {
  std::int64_t t_us = 0;
  Quat K_from_A = Quat::Identity();
  Vec3 specific_force_A = Vec3::Zero();
};

struct ShoulderSample {
  std::int64_t t_us = 0;
  Vec3 p_K = Vec3::Zero();
};

}  // namespace posefuse::forearm
