#include "imu/vector_observation.hpp"

#include <cmath>

namespace posefuse::imu {

const char* observation_status_name(ObservationStatus status) {
  switch (status) {
    case ObservationStatus::kOk: return "ok";
    case ObservationStatus::kNonFinite: return "non-finite accelerometer or magnetometer reading";
    case ObservationStatus::kNoGravity: return "accelerometer reading too small to give gravity";
    case ObservationStatus::kNoMagneticField: return "magnetometer reading too small";
    case ObservationStatus::kFieldAlongGravity:
      return "magnetic field parallel to gravity: heading undefined";
  }
  return "unknown";
}

Mat3 W_from_A_matrix_from_vectors(const Vec3& acc, const Vec3& mag, const ObservationLimits& limits,
                                  ObservationStatus* status) {
  ObservationStatus result = ObservationStatus::kOk;
  Mat3 W_from_A = Mat3::Identity();
  const double acc_norm = acc.norm();
  const double mag_norm = mag.norm();
  if (!std::isfinite(acc_norm) || !std::isfinite(mag_norm)) {
    result = ObservationStatus::kNonFinite;
  } else if (acc_norm < limits.min_acc_norm_m_s2) {
    result = ObservationStatus::kNoGravity;
  } else if (mag_norm < limits.min_mag_norm_uT) {
    result = ObservationStatus::kNoMagneticField;
  } else {
    const Vec3 up = acc / acc_norm;                 // g_hat
    const Vec3 west_unnormalised = up.cross(mag / mag_norm);  // g x m, |.| = sin(angle)
    const double sin_angle = west_unnormalised.norm();
    if (!(sin_angle >= limits.min_sin_acc_mag_angle)) {
      result = ObservationStatus::kFieldAlongGravity;
    } else {
      const Vec3 west = west_unnormalised / sin_angle;
      // (g x m) x g is already unit: both factors are unit and orthogonal.
      const Vec3 north = west.cross(up);
      W_from_A.row(0) = north;  // eq. 1, V'_X
      W_from_A.row(1) = west;   // eq. 1, V'_Y
      W_from_A.row(2) = up;     // eq. 1, V'_Z
    }
  }
  if (status != nullptr) *status = result;
  return W_from_A;
}

VectorObservation observe_W_from_A(const Vec3& acc, const Vec3& mag, const ObservationLimits& limits) {
  VectorObservation obs;
  const Mat3 W_from_A = W_from_A_matrix_from_vectors(acc, mag, limits, &obs.status);
  if (obs.ok()) obs.W_from_A = geometry::quat_from_rotation_matrix(W_from_A);
  return obs;
}

VectorObservation observe_W_from_A_near(const Vec3& acc, const Vec3& mag,
                                        const Quat& predicted_W_from_A,
                                        const ObservationLimits& limits) {
  VectorObservation obs = observe_W_from_A(acc, mag, limits);
  if (obs.ok()) obs.W_from_A = geometry::same_hemisphere(obs.W_from_A, predicted_W_from_A);  // eq. 2
  return obs;
}

}  // namespace posefuse::imu
