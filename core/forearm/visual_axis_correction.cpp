#include "forearm/visual_axis_correction.hpp"

#include <cmath>
#include <string>

#include "common/error.hpp"

namespace posefuse::forearm {

namespace {
constexpr double kPi = 3.14159265358979323846;
// A depth segment this short says nothing about the direction (the fit fell apart).
constexpr double kMinSegmentM = 0.05;

void check_gain(double gain, const char* name) {
  if (!(gain >= 0.0 && gain <= 1.0)) {
    throw_invalid(std::string("VisualAxisCorrectionOptions.") + name,
                  "is " + std::to_string(gain) + ", must be in [0, 1]");
  }
}
}  // namespace

VisualAxisCorrection::VisualAxisCorrection(const VisualAxisCorrectionOptions& options) : options_(options) {
  check_gain(options.gain_K, "gain_K");
  check_gain(options.gain_F, "gain_F");
  const double sum = options.gain_K + options.gain_F;
  if (!(sum > 0.0 && sum <= 1.0)) {
    throw_invalid("VisualAxisCorrectionOptions.gain_K",
                  "plus gain_F is " + std::to_string(sum) + ", must be in (0, 1]");
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
  const Quat K_from_F = correction_.K_from_F(K_from_F_imu);
  const Vec3 imu_axis = (K_from_F * Vec3::UnitY()).normalized();
  const Vec3 depth_axis = segment.normalized();
  const Vec3 cross = imu_axis.cross(depth_axis);
  const double angle = std::atan2(cross.norm(), imu_axis.dot(depth_axis));
  if (angle > options_.max_angle_rad) return false;
  if (cross.norm() > 1e-12) {
    const Vec3 turn_axis_K = cross.normalized();
    correction_.K_side =
        (Quat(Eigen::AngleAxisd(options_.gain_K * angle, turn_axis_K)) * correction_.K_side).normalized();
    // The same turn of the axis through F: rotating F by w_F turns y_K about K_from_F w_F.
    const Vec3 turn_axis_F = K_from_F.conjugate() * turn_axis_K;
    correction_.F_side =
        (correction_.F_side * Quat(Eigen::AngleAxisd(options_.gain_F * angle, turn_axis_F))).normalized();
  }
  ++frames_used_;
  return true;
}

}  // namespace posefuse::forearm
