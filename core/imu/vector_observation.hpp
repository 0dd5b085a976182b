#pragma once
// The analytic vector observation of paper 1, II-D: one accelerometer and one magnetometer
// reading give the sensor orientation W_from_A directly (eq. 1), as a quaternion by van
// Waveren's method, with the sign chosen next to the predicted orientation (eq. 2).
//
// W is x magnetic north, y magnetic west, z up. At rest the accelerometer reads +g along up,
// so g_hat (the measured acceleration direction, in A) is W's z axis seen from A. The field
// points north (and down, in the northern hemisphere), so up x field = west and west x up = north:
//   V'_X = (g x m) x g  (north),  V'_Y = g x m  (west),  V'_Z = g  (up)          (eq. 1)
// These are W's axes expressed in A, i.e. the columns of A_from_W. Their transpose, the matrix
// with V'_X, V'_Y, V'_Z as ROWS, is W_from_A: it maps v_A to (V'_X.v_A, V'_Y.v_A, V'_Z.v_A).
#include "geometry/quaternion.hpp"
#include "geometry/rotation_matrix.hpp"

namespace posefuse::imu {

using geometry::Mat3;
using geometry::Quat;
using geometry::Vec3;

// Why a reading pair gives no observation. The filter then only predicts.
enum class ObservationStatus {
  kOk,
  kNonFinite,          // a NaN or infinite component (a NaN magnetometer = no reading)
  kNoGravity,          // |acc| below ObservationLimits::min_acc_norm_m_s2 (free fall, zero)
  kNoMagneticField,    // |mag| below ObservationLimits::min_mag_norm_uT
  kFieldAlongGravity,  // field and gravity (nearly) parallel: heading undefined
};
const char* observation_status_name(ObservationStatus status);

struct ObservationLimits {
  double min_acc_norm_m_s2 = 1e-3;
  double min_mag_norm_uT = 1e-3;
  // Smallest allowed sin(angle between acc and mag). Below it the cross product g x m is so short
  // that sensor noise turns the heading at random; 0.05 is ~2.9 degrees. (The earth field is
  // >= 0 degrees from vertical only at the magnetic poles; a clinic never sees that, a magnet
  // next to the sensor can.)
  double min_sin_acc_mag_angle = 0.05;
};

// A vector observation: `W_from_A` is meaningful only when status == kOk (it is the identity
// otherwise, never NaN).
struct VectorObservation {
  ObservationStatus status = ObservationStatus::kNonFinite;
  Quat W_from_A = Quat::Identity();
  bool ok() const { return status == ObservationStatus::kOk; }
};

// Eq. 1 as a matrix: rows V'_X, V'_Y, V'_Z normalised. Only valid when `status` (optional
// output) is kOk; the identity otherwise.
Mat3 W_from_A_matrix_from_vectors(const Vec3& acc_m_s2, const Vec3& mag_uT, const ObservationLimits& limits,
                                  ObservationStatus* status);

// Eq. 1 + van Waveren: the observed W_from_A, with whatever sign van Waveren's pivot gives.
VectorObservation observe_W_from_A(const Vec3& acc_m_s2, const Vec3& mag_uT, const ObservationLimits& limits = {});

// Eq. 1 + van Waveren + eq. 2: the observed W_from_A as the member of {q, -q} on the side of
// `predicted_W_from_A` (non-negative dot product), so the filter never averages across the sign.
VectorObservation observe_W_from_A_near(const Vec3& acc_m_s2, const Vec3& mag_uT, const Quat& predicted_W_from_A,
                                        const ObservationLimits& limits = {});

}  // namespace posefuse::imu
