#include "imu/kalman_orientation_filter.hpp"

#include <cmath>
#include <string>

#include "common/error.hpp"

namespace posefuse::imu {

namespace {

// q (x) [0, v] = Omega(v) q for q = [w x y z] (right multiplication by a pure quaternion).
Mat4 omega(const Vec3& v) {
  Mat4 m;
  // clang-format off
  m <<  0.0,   -v.x(), -v.y(), -v.z(),
        v.x(),  0.0,    v.z(), -v.y(),
        v.y(), -v.z(),  0.0,    v.x(),
        v.z(),  v.y(), -v.x(),  0.0;
  // clang-format on
  return m;
}

void require_positive(double value, const char* field) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw_invalid(field, "must be positive and finite, got " + std::to_string(value));
  }
}

}  // namespace

Mat4 quaternion_transition_matrix(const Vec3& rate, double dt) {
  // exp(0.5 Omega(w) dt) is right multiplication by exp of the rotation vector w dt, whose
  // quaternion quat_from_rotation_vector computes exactly (and stably near zero rate).
  const Quat delta = geometry::quat_from_rotation_vector(rate * dt);
  return delta.w() * Mat4::Identity() + omega(delta.vec());
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
    throw_invalid("imu[" + std::to_string(sample_index_) + "].t_us",
                  "timestamp " + std::to_string(sample.t_us) + " is not after the previous one (" +
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
  const VectorObservation obs = observe_W_from_A(sample.acc_m_s2, sample.mag_uT,
                                                 params_.observation_limits);
  if (!obs.ok()) {
    const char* field = obs.status == ObservationStatus::kNoGravity ? "acc_m_s2" : "mag_uT";
    throw_precondition("imu[" + std::to_string(sample_index_) + "]." + field,
                       std::string("the first sample must give an orientation to start from: ") +
                           observation_status_name(obs.status));
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
    const Vec3& bias = params_.track_gyro_bias ? bias_tracker_.update(sample.gyr_rad_s)
                                               : params_.gyro_bias.initial_bias_rad_s;
    if (dt_s <= params_.max_prediction_dt_s) {
      predict(sample.gyr_rad_s - bias, dt_s);
    } else {
      P_ = initial_variance_ * Mat4::Identity();
    }
    const VectorObservation obs = observe_W_from_A_near(
        sample.acc_m_s2, sample.mag_uT, W_from_A(), params_.observation_limits);  // eq. 1, 2
    if (obs.ok()) {
      const Quat& z = obs.W_from_A;
      correct(Vec4(z.w(), z.x(), z.y(), z.z()));
    }
  }
  last_t_us_ = sample.t_us;
  ++sample_index_;
  return W_from_A();
}

void KalmanOrientationFilter::predict(const Vec3& rate_rad_s, double dt_s) {
  const Mat4 Phi = quaternion_transition_matrix(rate_rad_s, dt_s);
  q_ = Phi * q_;
  q_.normalize();
  const double half_angle_sigma = 0.5 * params_.gyro_noise_rad_s * dt_s;
  const Mat4 Q = (half_angle_sigma * half_angle_sigma) * (Mat4::Identity() - q_ * q_.transpose());
  P_ = Phi * P_ * Phi.transpose() + Q;
}

void KalmanOrientationFilter::correct(const Vec4& observed) {
  // H = I: S = P + R, K = P S^-1.
  Mat4 S = P_;
  S.diagonal().array() += observation_variance_;
  const Mat4 K = P_ * S.inverse();
  q_ += K * (observed - q_);
  q_.normalize();
  P_ = (Mat4::Identity() - K) * P_;
  P_ = 0.5 * (P_ + P_.transpose()).eval();  // keep P symmetric against rounding
}

}  // namespace posefuse::imu
