#pragma once
// Paper 1's evaluation metrics (III): forearm orientation error (eqs. 14-15), the camera SDK's
// IMU position estimate (eq. 16), and RMS / maximum over selected frames (Table I), used by
// bench/bench_table1 and its tests.
#include <cstddef>
#include <vector>

#include "geometry/quaternion.hpp"

namespace posefuse::eval {

using geometry::Quat;
using geometry::Vec3;

// Eqs. 14-15: deg' = 2 acos(Re(q_measured^-1 q_gold)) in degrees, error = min(deg', 360 - deg').
// Sign-invariant (q and -q give the same error); inputs need not be normalised. Degrees, in
// [0, 180].
double paper_orientation_error_deg(const Quat& K_from_F_measured, const Quat& K_from_F_gold);

// Eq. 16: the SDK's IMU position, interpolated between its elbow L and wrist T at the strap's
// place d_se / (d_se + d_sw). posefuse::Error for non-positive or non-finite lengths.
Vec3 sdk_imu_position(const Vec3& elbow_K, const Vec3& wrist_K, double d_se_m, double d_sw_m);

// RMS and maximum of the finite errors whose frame is selected (Table I's rows; "inside gaps
// only" selects the occluded frames). count = errors that entered; with none, rms and max are
// NaN.
struct ErrorSummary {
  double rms = 0.0;
  double max = 0.0;
  std::size_t count = 0;
};
// `selected` empty selects every frame; otherwise sizes must match (posefuse::Error).
ErrorSummary summarize_errors(const std::vector<double>& errors, const std::vector<bool>& selected = {});

// Table I's "error reduction": 100 (1 - fusion / sdk) percent.
double error_reduction_percent(double sdk, double fusion);

}  // namespace posefuse::eval
