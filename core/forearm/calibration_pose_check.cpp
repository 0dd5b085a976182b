#include "forearm/calibration_pose_check.hpp"

#include <cmath>

namespace posefuse::forearm {
namespace {

bool usable_direction(const Vec3& v) { return v.allFinite() && v.norm() >= 1e-6; }

}  // namespace

bool forearm_raised_for_calibration(const Vec3& elbow_K, const Vec3& wrist_K, const Vec3& up_K, double max_tilt_rad) {
  const Vec3 forearm = wrist_K - elbow_K;
  if (!usable_direction(forearm) || !usable_direction(up_K)) return false;
  return forearm.normalized().dot(up_K.normalized()) >= std::cos(max_tilt_rad);
}

bool upper_arm_lowered_for_calibration(const Vec3& shoulder_K, const Vec3& elbow_K, const Vec3& up_K,
                                       double max_rise_rad) {
  const Vec3 upper_arm = elbow_K - shoulder_K;
  if (!usable_direction(upper_arm) || !usable_direction(up_K)) return false;
  return upper_arm.normalized().dot(up_K.normalized()) <= std::sin(max_rise_rad);
}

bool elbow_flexed_for_calibration(const Vec3& shoulder_K, const Vec3& elbow_K, const Vec3& wrist_K,
                                  double min_flexion_rad) {
  const Vec3 upper_arm = elbow_K - shoulder_K, forearm = wrist_K - elbow_K;
  if (!usable_direction(upper_arm) || !usable_direction(forearm)) return false;
  return upper_arm.normalized().dot(forearm.normalized()) <= std::cos(min_flexion_rad);
}

}  // namespace posefuse::forearm
