#include "forearm/visual_axis_correction.hpp"

#include <cmath>
#include <string>

#include "common/error.hpp"

namespace posefuse::forearm {

namespace {
constexpr double kPi = 3.14159265358979323846;
// A depth segment this short says nothing about the direction (the fit fell apart).
constexpr double kMinSegmentM = 0.05;
}  // namespace

VisualAxisCorrection::VisualAxisCorrection(const VisualAxisCorrectionOptions& options) : options_(options) {
  if (!(options.gain > 0.0 && options.gain <= 1.0)) {
    throw_invalid("VisualAxisCorrectionOptions.gain", "is " + std::to_string(options.gain) + ", must be in (0, 1]");
  }
  if (!(options.max_angle_rad > 0.0 && options.max_angle_rad <= kPi / 2)) {
    throw_invalid("VisualAxisCorrectionOptions.max_angle_rad",
                  "is " + std::to_string(options.max_angle_rad) + ", must be in (0, pi/2]");
  }
}

bool VisualAxisCorrection::observe(const Quat& K_from_F_imu, const Vec3& elbow_K, const Vec3& wrist_K) {
  if (!K_from_F_imu.coeffs().allFinite() || !elbow_K.allFinite() || !wrist_K.allFinite()) return false;
  const Vec3 segment = wrist_K - elbow_K;
  if (segment.norm() < kMinSegmentM) return false;
  const Vec3 imu_axis = (apply(K_from_F_imu) * Vec3::UnitY()).normalized();
  const Vec3 depth_axis = segment.normalized();
  const Vec3 cross = imu_axis.cross(depth_axis);
  const double angle = std::atan2(cross.norm(), imu_axis.dot(depth_axis));
  if (angle > options_.max_angle_rad) return false;
  if (cross.norm() > 1e-12) {
    const Quat step(Eigen::AngleAxisd(options_.gain * angle, cross.normalized()));
    K_correction_ = (step * K_correction_).normalized();
  }
  ++frames_used_;
  return true;
}

}  // namespace posefuse::forearm
