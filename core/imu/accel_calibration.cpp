#include "imu/accel_calibration.hpp"

#include <cmath>
#include <string>

#include "common/error.hpp"

namespace posefuse::imu {

AccelCalibrationResult calibrate_accelerometer(const std::vector<Vec3>& means, const AccelCalibrationParams& params) {
  constexpr const char* kField = "acc_samples";
  if (!(params.gravity_m_s2 > 0.0) || !std::isfinite(params.gravity_m_s2)) {
    throw_invalid("accel.gravity_m_s2", "must be positive and finite, got " + std::to_string(params.gravity_m_s2));
  }
  if (means.size() < params.min_orientations) {
    throw_precondition(kField, std::to_string(means.size()) + " still orientations, need at least " +
                                   std::to_string(params.min_orientations) + " (paper: more than 30)");
  }
  const EllipsoidFit fit = fit_ellipsoid(means, kField, params.max_condition_number);
  AccelCalibrationResult result;
  result.calibration.offset_m_s2 = fit.center;
  result.calibration.correction = fit.sphere_from_ellipsoid(params.gravity_m_s2);
  AccelCalibrationReport& report = result.report;
  report.orientation_count = means.size();
  report.condition_number = fit.condition_number;
  report.relative_spread_before = relative_norm_spread(means, Mat3::Identity(), Vec3::Zero());
  report.relative_spread_after =
      relative_norm_spread(means, result.calibration.correction, result.calibration.offset_m_s2);
  return result;
}

}  // namespace posefuse::imu
