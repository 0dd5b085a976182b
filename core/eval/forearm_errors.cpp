#include "eval/forearm_errors.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "common/error.hpp"

namespace posefuse::eval {

double paper_orientation_error_deg(const Quat& measured, const Quat& gold) {
  const Quat q = measured.normalized().conjugate() * gold.normalized();
  const double real = std::clamp(q.w(), -1.0, 1.0);
  const double deg_prime = std::acos(real) * 360.0 / 3.14159265358979323846;  // eq. 14, in [0, 360]
  return std::min(deg_prime, 360.0 - deg_prime);                              // eq. 15
}

Vec3 sdk_imu_position(const Vec3& elbow_K, const Vec3& wrist_K, double d_se_m, double d_sw_m) {
  if (!(std::isfinite(d_se_m) && d_se_m > 0.0))
    throw_invalid("d_se_m", "is " + std::to_string(d_se_m) + ", must be > 0");
  if (!(std::isfinite(d_sw_m) && d_sw_m > 0.0))
    throw_invalid("d_sw_m", "is " + std::to_string(d_sw_m) + ", must be > 0");
  return elbow_K + d_se_m / (d_sw_m + d_se_m) * (wrist_K - elbow_K);  // eq. 16
}

ErrorSummary summarize_errors(const std::vector<double>& errors, const std::vector<bool>& selected) {
  if (!selected.empty() && selected.size() != errors.size()) {
    throw_invalid("selected",
                  "has " + std::to_string(selected.size()) + " flags for " + std::to_string(errors.size()) + " errors");
  }
  ErrorSummary s;
  double sum_sq = 0.0;
  for (std::size_t i = 0; i < errors.size(); ++i) {
    if ((!selected.empty() && !selected[i]) || !std::isfinite(errors[i])) continue;
    sum_sq += errors[i] * errors[i];
    s.max = std::max(s.max, std::abs(errors[i]));
    ++s.count;
  }
  if (s.count == 0) {
    s.rms = s.max = std::numeric_limits<double>::quiet_NaN();
  } else {
    s.rms = std::sqrt(sum_sq / static_cast<double>(s.count));
  }
  return s;
}

double error_reduction_percent(double sdk, double fusion) { return 100.0 * (1.0 - fusion / sdk); }

}  // namespace posefuse::eval
