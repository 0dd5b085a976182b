#include "imu/vector_observation.hpp"

#include <cmath>

namespace posefuse::imu {

const char* observation_status_name(ObservationStatus status) {
  switch (status) {
    case ObservationStatus::kOk: return "ok";
    case ObservationStatus::kNonFinite: return "non-finite accelerometer or magnetometer reading";
    case ObservationStatus::kNoGravity: return "accelerometer reading too small to give gravity";
    case ObservationStatus::kNoMagneticField: return "magnetometer reading too small";
    case ObservationStatus::kFieldAlongGravity: return "magnetic field parallel to gravity: heading undefined";
  }
  return "unknown";
}

Mat3 W_from_A_matrix_from_vectors(const Vec3& acc, const Vec3& mag, const ObservationLimits& limits,
                                  ObservationStatus* status) {
  // Squared norms and one cross product decide everything; only the two directions that are
  // used need a square root (this runs once per filter sample).
  ObservationStatus result = ObservationStatus::kOk;
  Mat3 W_from_A = Mat3::Identity();
  const double acc_sq = acc.squaredNorm();
  const double mag_sq = mag.squaredNorm();
  const Vec3 acc_cross_mag = acc.cross(mag);  // |.| = |acc| |mag| sin(angle)
  const double cross_sq = acc_cross_mag.squaredNorm();
  const double min_sin = limits.min_sin_acc_mag_angle;
  if (!std::isfinite(acc_sq) || !std::isfinite(mag_sq) || !std::isfinite(cross_sq)) {
    result = ObservationStatus::kNonFinite;
  } else if (!(acc_sq >= limits.min_acc_norm_m_s2 * limits.min_acc_norm_m_s2)) {
    result = ObservationStatus::kNoGravity;
  } else if (!(mag_sq >= limits.min_mag_norm_uT * limits.min_mag_norm_uT)) {
    result = ObservationStatus::kNoMagneticField;
  } else if (!(cross_sq >= min_sin * min_sin * acc_sq * mag_sq) || !(cross_sq > 0.0)) {
    result = ObservationStatus::kFieldAlongGravity;
  } else {
    const Vec3 up = acc * (1.0 / std::sqrt(acc_sq));                // g_hat
    const Vec3 west = acc_cross_mag * (1.0 / std::sqrt(cross_sq));  // g x m, normalised
    const Vec3 north = west.cross(up);  // (g x m) x g: unit, both factors unit and orthogonal
    W_from_A.row(0) = north;            // eq. 1, V'_X
    W_from_A.row(1) = west;             // eq. 1, V'_Y
    W_from_A.row(2) = up;               // eq. 1, V'_Z
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

VectorObservation observe_W_from_A_near(const Vec3& acc, const Vec3& mag, const Quat& predicted_W_from_A,
                                        const ObservationLimits& limits) {
  VectorObservation obs = observe_W_from_A(acc, mag, limits);
  if (obs.ok()) obs.W_from_A = geometry::same_hemisphere(obs.W_from_A, predicted_W_from_A);  // eq. 2
  return obs;
}

}  // namespace posefuse::imu
