#include "eval/orientation_error.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "common/error.hpp"

namespace posefuse::eval {

OrientationError orientation_error(const Quat& est, const Quat& gt) {
  const Quat q = (est.normalized() * gt.normalized().conjugate()).normalized();
  const double w = std::abs(q.w());
  OrientationError e;
  e.total_rad = 2.0 * std::acos(std::min(1.0, w));
  // atan2 instead of atan(|z/w|): identical for w > 0 and defined when w == 0.
  e.heading_rad = 2.0 * std::atan2(std::abs(q.z()), w);
  e.inclination_rad = 2.0 * std::acos(std::min(1.0, std::sqrt(q.w() * q.w() + q.z() * q.z())));
  return e;
}

OrientationRmse orientation_rmse(const std::vector<Quat>& est, const std::vector<Quat>& gt,
                                 const std::vector<bool>& counted) {
  if (est.size() != gt.size()) {
    throw_invalid("ref_from_sensor_est",
                  "has " + std::to_string(est.size()) + " samples, ground truth has " + std::to_string(gt.size()));
  }
  if (counted.size() != gt.size()) {
    throw_invalid("counted",
                  "has " + std::to_string(counted.size()) + " entries, ground truth has " + std::to_string(gt.size()));
  }
  double sum_total = 0.0, sum_heading = 0.0, sum_inclination = 0.0;
  OrientationRmse r;
  for (std::size_t i = 0; i < gt.size(); ++i) {
    if (!counted[i] || !gt[i].coeffs().allFinite()) continue;
    if (!est[i].coeffs().allFinite()) {
      throw_invalid("ref_from_sensor_est[" + std::to_string(i) + "]", "not finite");
    }
    const OrientationError e = orientation_error(est[i], gt[i]);
    sum_total += e.total_rad * e.total_rad;
    sum_heading += e.heading_rad * e.heading_rad;
    sum_inclination += e.inclination_rad * e.inclination_rad;
    ++r.samples;
  }
  if (r.samples == 0) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    r.total_rad = r.heading_rad = r.inclination_rad = nan;
    return r;
  }
  const double n = static_cast<double>(r.samples);
  r.total_rad = std::sqrt(sum_total / n);
  r.heading_rad = std::sqrt(sum_heading / n);
  r.inclination_rad = std::sqrt(sum_inclination / n);
  return r;
}

}  // namespace posefuse::eval
