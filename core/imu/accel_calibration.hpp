#pragma once
// Optional accelerometer calibration (paper 1, II-E-3).
//
// The sensor is held still in many orientations; in each one the mean reading is gravity seen
// through the sensor's offset and scale/misalignment errors, so the means lie on an ellipsoid.
// The same ellipsoid fit as the magnetometer's (fit_ellipsoid) gives offset o and the symmetric
// correction C = g H diag(1/alpha, 1/beta, 1/gamma) H^T with |C (a - o)| = g in every orientation.
// A magnitude-only calibration cannot see a pure rotation of the sensor axes, so C is the
// symmetric (6-parameter) scale/misalignment matrix; axis rotation belongs to the mounting
// calibration. The paper uses the factory calibration because > 30 orientations need a
// rotation stage or robot arm; the default AccelCalibration is that identity.
#include <cstddef>
#include <vector>

#include "imu/ellipsoid_fit.hpp"

namespace posefuse::imu {

struct AccelCalibrationParams {
  double gravity_m_s2 = 9.80665;  // local g; standard gravity by default
  // 9 orientations determine the 9 quadric coefficients exactly (no noise averaging); the paper
  // asks for more than 30. Fewer than this are refused.
  std::size_t min_orientations = 9;
  // See EllipsoidFit::condition_number. Orientations that leave an axis never pointing (close
  // to) up or down, or lie in a plane, exceed it.
  double max_condition_number = 100.0;
};

// Default-constructed: the factory calibration (identity, zero offset).
struct AccelCalibration {
  Vec3 offset_m_s2 = Vec3::Zero();     // o
  Mat3 correction = Mat3::Identity();  // C, symmetric positive definite
  Vec3 apply(const Vec3& raw_m_s2) const { return correction * (raw_m_s2 - offset_m_s2); }
};

struct AccelCalibrationReport {
  std::size_t orientation_count = 0;
  double relative_spread_before = 0.0;  // std/mean of |a| over the orientations, raw
  double relative_spread_after = 0.0;   // the same after calibration
  double condition_number = 0.0;
};

struct AccelCalibrationResult {
  AccelCalibration calibration;
  AccelCalibrationReport report;
};

// `static_mean_acc_m_s2`: one mean reading per still orientation (average ~1 s of samples each).
// Throws posefuse::Error kFailedPrecondition, field "acc_samples", when there are fewer than
// min_orientations, the fit is ill-conditioned, or it is not an ellipsoid; kInvalidArgument
// ("acc_samples[i]") on a non-finite reading or bad params ("accel.gravity_m_s2").
AccelCalibrationResult calibrate_accelerometer(const std::vector<Vec3>& static_mean_acc_m_s2,
                                               const AccelCalibrationParams& params = {});

}  // namespace posefuse::imu
