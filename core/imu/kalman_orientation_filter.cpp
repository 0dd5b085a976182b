#include "imu/kalman_orientation_filter.hpp"

#include <cmath>
#include <string>

#include "common/error.hpp"

namespace posefuse::imu {

namespace {

void require_positive(double value, const char* field) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw_invalid(field, "must be positive and finite, got " + std::to_string(value));
  }
}

}  // namespace

Mat4 quaternion_transition_matrix(const Vec3& rate, double dt) {
  // exp(0.5 Omega(w) dt) = cos(h) I + (sin(h) / |w|) Omega(w) with h = |w| dt / 2 (Omega^2 =
  // -|w|^2 I), where q (x) [0, v] = Omega(v) q. Per-sample half angles are small (h < 0.05 up
  // to 8 rad/s at 80 Hz), where the Taylor series below equal cos and sin(h)/h to within double
  // rounding (the first omitted terms are < 0.05^10 / 10! ~ 3e-20) at a fraction of the cost of
  // the library calls.
  const double half_dt = 0.5 * dt;
  const double h2 = rate.squaredNorm() * half_dt * half_dt;  // h^2
  double c, sin_h_over_h;
  if (h2 < 0.05 * 0.05) {
    c = 1.0 + h2 * (-1.0 / 2 + h2 * (1.0 / 24 + h2 * (-1.0 / 720 + h2 * (1.0 / 40320))));
    sin_h_over_h = 1.0 + h2 * (-1.0 / 6 + h2 * (1.0 / 120 + h2 * (-1.0 / 5040 + h2 * (1.0 / 362880))));
  } else {
    const double h = std::sqrt(h2);
    c = std::cos(h);
    sin_h_over_h = std::sin(h) / h;
  }
  const Vec3 v = (sin_h_over_h * half_dt) * rate;  // sin(h) w / |w|
  Mat4 Phi;                                        // c I + Omega(v), column by column
  Phi.col(0) = Vec4(c, v.x(), v.y(), v.z());
  Phi.col(1) = Vec4(-v.x(), c, -v.z(), v.y());
  Phi.col(2) = Vec4(-v.y(), v.z(), c, -v.x());
  Phi.col(3) = Vec4(-v.z(), -v.y(), v.x(), c);
  return Phi;
}

KalmanOrientationFilter::KalmanOrientationFilter(const Params& params)
    : params_(params), bias_tracker_(params.gyro_bias) {
  require_positive(params.gyro_noise_rad_s, "kalman.gyro_noise_rad_s");
  require_positive(params.observation_noise_rad, "kalman.observation_noise_rad");
  require_positive(params.initial_angle_sigma_rad, "kalman.initial_angle_sigma_rad");
  require_positive(params.max_prediction_dt_s, "kalman.max_prediction_dt_s");
  initial_variance_ = 0.25 * params.initial_angle_sigma_rad * params.initial_angle_sigma_rad;
  observation_variance_ = 0.25 * params.observation_noise_rad * params.observation_noise_rad;
}

void KalmanOrientationFilter::reset() {
  bias_tracker_.reset();
  initialised_ = false;
  last_t_us_ = 0;
  sample_index_ = 0;
  q_ = Vec4(1, 0, 0, 0);
  P_.setIdentity();
}

Quat KalmanOrientationFilter::update(const ImuSample& sample) {
  validate_imu_sample(sample, "imu", sample_index_);
  if (initialised_ && sample.t_us <= last_t_us_) {
    throw_invalid("imu[" + std::to_string(sample_index_) + "].t_us", "timestamp " + std::to_string(sample.t_us) +
                                                                         " is not after the previous one (" +
                                                                         std::to_string(last_t_us_) + ")");
  }
  return step(sample);
}

std::vector<Quat> KalmanOrientationFilter::process(const std::vector<ImuSample>& samples) {
  validate_imu_stream(samples, "imu");
  reset();
  std::vector<Quat> W_from_A;
  W_from_A.reserve(samples.size());
  for (const ImuSample& sample : samples) W_from_A.push_back(step(sample));
  return W_from_A;
}

void KalmanOrientationFilter::initialise(const ImuSample& sample) {
  const VectorObservation obs = observe_W_from_A(sample.acc_m_s2, sample.mag_uT, params_.observation_limits);
  if (!obs.ok()) {
    const char* field = obs.status == ObservationStatus::kNoGravity ? "acc_m_s2" : "mag_uT";
    throw_precondition(
        "imu[" + std::to_string(sample_index_) + "]." + field,
        std::string("the first sample must give an orientation to start from: ") + observation_status_name(obs.status));
  }
  const Quat& q = obs.W_from_A;
  q_ = Vec4(q.w(), q.x(), q.y(), q.z());
  P_ = initial_variance_ * Mat4::Identity();
  if (params_.track_gyro_bias) bias_tracker_.update(sample.gyr_rad_s);
  initialised_ = true;
}

Quat KalmanOrientationFilter::step(const ImuSample& sample) {
  if (!initialised_) {
    initialise(sample);
  } else {
    const double dt_s = 1e-6 * static_cast<double>(sample.t_us - last_t_us_);
    const Vec3& bias =
        params_.track_gyro_bias ? bias_tracker_.update(sample.gyr_rad_s) : params_.gyro_bias.initial_bias_rad_s;
    if (dt_s <= params_.max_prediction_dt_s) {
      predict(sample.gyr_rad_s - bias, dt_s);
    } else {
      P_ = initial_variance_ * Mat4::Identity();
    }
    const VectorObservation obs =
        observe_W_from_A_near(sample.acc_m_s2, sample.mag_uT, W_from_A(), params_.observation_limits);  // eq. 1, 2
    if (obs.ok()) {
      const Quat& z = obs.W_from_A;
      correct(Vec4(z.w(), z.x(), z.y(), z.z()));
    }
  }
  q_ *= 1.0 / q_.norm();
  last_t_us_ = sample.t_us;
  ++sample_index_;
  return W_from_A();
}

void KalmanOrientationFilter::predict(const Vec3& rate_rad_s, double dt_s) {
  const Mat4 Phi = quaternion_transition_matrix(rate_rad_s, dt_s);
  q_ = Phi * q_;  // Phi is orthogonal: |q| is kept to rounding; step() renormalises
  const double half_angle_sigma = 0.5 * params_.gyro_noise_rad_s * dt_s;
  const double q_scale = half_angle_sigma * half_angle_sigma;
  Mat4 Phi_P;
  Phi_P.noalias() = Phi * P_;
  P_.noalias() = Phi_P * Phi.transpose();
  P_ += q_scale * (Mat4::Identity() - q_ * q_.transpose());  // Q = q_scale (I - q q^T)
}

void KalmanOrientationFilter::correct(const Vec4& observed) {
  // H = I, R = r I: S = P + r I, K = P S^-1 = I - r S^-1, so
  //   q+ = q + K (z - q) = z - r S^-1 (z - q),   P+ = (I - K) P = r S^-1 P,
  // the textbook update with one 4x4 product fewer and no subtraction of near-equal matrices.
  const double r = observation_variance_;
  // Whole-matrix expressions: adding to the diagonal in place makes scalar stores that the
  // following packed loads wait for (measured: ~40% of this function).
  const Mat4 S = P_ + r * Mat4::Identity();
  const Mat4 S_inverse = S.inverse();
  q_ = observed - r * (S_inverse * (observed - q_));  // step() renormalises
  const Mat4 P_next = r * (S_inverse * P_);
  P_ = 0.5 * (P_next + P_next.transpose());  // keep P symmetric against rounding
}

}  // namespace posefuse::imu
