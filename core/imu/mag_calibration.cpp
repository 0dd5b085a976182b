#include "imu/mag_calibration.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>

#include "common/error.hpp"

namespace posefuse::imu {

namespace {

constexpr int kBands = 8;
constexpr int kSectors = kDirectionBins / kBands;
constexpr const char* kField = "mag_samples";

std::string percent(double fraction) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.0f%%", 100.0 * fraction);
  return buffer;
}

void require_coverage(double coverage, double minimum, const char* when) {
  if (coverage < minimum) {
    throw_precondition(kField, std::string("readings ") + when + " cover " + percent(coverage) +
                                   " of the directions, need " + percent(minimum) +
                                   ": rotate the sensor in all directions, not in one plane");
  }
}

}  // namespace

double direction_coverage(const std::vector<Vec3>& points, const Vec3& center, const Mat3& linear) {
  std::array<bool, kDirectionBins> hit{};
  for (const Vec3& p : points) {
    const Vec3 d = linear * (p - center);
    const double norm = d.norm();
    if (!(norm > 0.0) || !std::isfinite(norm)) continue;
    const double z = d.z() / norm;
    const int band = std::clamp(static_cast<int>((z + 1.0) * 0.5 * kBands), 0, kBands - 1);
    const double longitude = std::atan2(d.y(), d.x()) + EIGEN_PI;  // [0, 2 pi]
    const int sector = std::clamp(static_cast<int>(longitude / (2.0 * EIGEN_PI) * kSectors), 0, kSectors - 1);
    hit[static_cast<std::size_t>(band * kSectors + sector)] = true;
  }
  return static_cast<double>(std::count(hit.begin(), hit.end(), true)) / kDirectionBins;
}

MagCalibrationResult calibrate_magnetometer(const std::vector<Vec3>& raw, const MagCalibrationParams& params) {
  MagCalibrationResult result;
  MagCalibrationReport& report = result.report;
  std::vector<Vec3> usable;
  usable.reserve(raw.size());
  for (std::size_t i = 0; i < raw.size(); ++i) {
    if (raw[i].array().isInf().any()) {
      throw_invalid(std::string(kField) + "[" + std::to_string(i) + "]", "infinite");
    }
    if (raw[i].array().isNaN().any()) {
      ++report.missing_count;
    } else {
      usable.push_back(raw[i]);
    }
  }
  report.sample_count = usable.size();
  if (usable.size() < params.min_samples) {
    throw_precondition(kField, std::to_string(usable.size()) + " usable readings (" +
                                   std::to_string(report.missing_count) + " missing), need " +
                                   std::to_string(params.min_samples) +
                                   ": rotate the sensor longer (paper: ~3000 samples)");
  }

  // Before fitting: a sensor turned in one plane gives a ring, which no fit can make a sphere of.
  Vec3 mean = Vec3::Zero();
  for (const Vec3& p : usable) mean += p;
  mean /= static_cast<double>(usable.size());
  require_coverage(direction_coverage(usable, mean), params.min_direction_coverage, "seen from their mean");

  const EllipsoidFit fit = fit_ellipsoid(usable, kField, params.max_condition_number);
  MagCalibration& cal = result.calibration;
  cal.center_uT = fit.center;
  cal.radii_uT = fit.radii;
  cal.axes = fit.axes;
  cal.field_strength_uT = std::cbrt(fit.radii.prod());
  cal.correction = fit.sphere_from_ellipsoid(cal.field_strength_uT);  // eq. 3, in uT

  report.condition_number = fit.condition_number;
  report.relative_spread_before = relative_norm_spread(usable, Mat3::Identity(), Vec3::Zero());
  report.relative_spread_after = relative_norm_spread(usable, cal.correction, cal.center_uT);
  report.direction_coverage = direction_coverage(usable, cal.center_uT, cal.correction);
  require_coverage(report.direction_coverage, params.min_direction_coverage, "after calibration");
  return result;
}

}  // namespace posefuse::imu
