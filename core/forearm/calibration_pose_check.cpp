#include "forearm/calibration_pose_check.hpp"

#include <cmath>

namespace posefuse::forearm {

bool forearm_raised_for_calibration(const Vec3& elbow_K, const Vec3& wrist_K, const Vec3& up_K, double max_tilt_rad) {
  const Vec3 forearm = wrist_K - elbow_K;
  if (!forearm.allFinite() || !up_K.allFinite() || forearm.norm() < 1e-6 || up_K.norm() < 1e-6) return false;
  return forearm.normalized().dot(up_K.normalized()) >= std::cos(max_tilt_rad);
}

}  // namespace posefuse::forearm
