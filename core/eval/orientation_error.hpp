#pragma once
// Orientation error metrics as the BROAD dataset defines them (Laidig et al., Data 6(7):72, 2021).
//
// Both quaternions map sensor vectors to the same reference frame whose z axis points up
// (e.g. sensor->ENU). The error q_err = q_est * q_gt^-1 is split into a rotation about the
// vertical (heading) and the remaining rotation about a horizontal axis (inclination).
#include <cstddef>
#include <vector>

#include "geometry/quaternion.hpp"

namespace posefuse::eval {

using geometry::Quat;

struct OrientationError {
  double total_rad = 0.0;        // 2 acos(|w|)
  double heading_rad = 0.0;      // 2 atan(|z / w|)
  double inclination_rad = 0.0;  // 2 acos(sqrt(w^2 + z^2))
};

// Error of one estimate against the ground truth; inputs need not be normalised.
OrientationError orientation_error(const Quat& ref_from_sensor_est, const Quat& ref_from_sensor_gt);

struct OrientationRmse {
  double total_rad = 0.0;
  double heading_rad = 0.0;
  double inclination_rad = 0.0;
  std::size_t samples = 0;  // samples that entered the RMSE
};

// RMSE over the samples with `counted[i]` true whose ground truth is finite (BROAD skips NaN
// rows where markers were lost). Sizes must match (posefuse::Error otherwise); if no sample
// counts, the result has samples = 0 and NaN errors.
OrientationRmse orientation_rmse(const std::vector<Quat>& ref_from_sensor_est,
                                 const std::vector<Quat>& ref_from_sensor_gt, const std::vector<bool>& counted);

}  // namespace posefuse::eval
