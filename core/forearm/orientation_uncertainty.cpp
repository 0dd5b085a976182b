#include "forearm/orientation_uncertainty.hpp"

#include <cmath>
#include <limits>

namespace posefuse::forearm {

double orientation_rms_rad(double axis_rms_rad, double roll_rms_rad, double filter_rms_rad) {
  return std::sqrt(axis_rms_rad * axis_rms_rad + roll_rms_rad * roll_rms_rad + filter_rms_rad * filter_rms_rad);
}

double forearm_axis_rms_rad(double axis_rms_rad, double filter_rms_rad) {
  return std::hypot(axis_rms_rad, kDirectionRmsOverOrientationRms * filter_rms_rad);
}

double pose_calibration_rms_rad(double hold_spread_rad) {
  if (!(hold_spread_rad >= 0.0)) return std::nan("");
  return std::hypot(kPoseCalibrationRmsRad, hold_spread_rad);
}

double imu_orientation_rms_rad(double beyond_steady_rad) { return std::hypot(kFilterRmsRad, beyond_steady_rad); }

double confidence_from_bound99_rad(double bound99_rad) {
  if (!(bound99_rad >= 0.0)) return 0.0;
  const double bound_ratio = bound99_rad / kConfidentErrorBoundRad;
  return std::exp2(-bound_ratio * bound_ratio);
}

double bound99_rad_from_confidence(double confidence) {
  if (!(confidence > 0.0)) return std::numeric_limits<double>::infinity();
  if (confidence >= 1.0) return 0.0;
  return kConfidentErrorBoundRad * std::sqrt(-std::log2(confidence));
}

double confidence_from_rms_rad(double rms_rad) { return confidence_from_bound99_rad(kBound99OverRms * rms_rad); }

double direction_confidence_from_rms_rad(double rms_rad) {
  return confidence_from_bound99_rad(kDirectionBound99OverRms * rms_rad);
}

}  // namespace posefuse::forearm
