#pragma once
// The quaternion Kalman orientation filter of paper 1, II-D (after Comotti et al., ref. [15]),
// with the paper's analytic vector observation (eq. 1, 2) and gyro bias tracking (II-E-2).
//
// State: the unit quaternion W_from_A as [w x y z] with its 4x4 covariance P.
// Prediction (bias-corrected gyro w = gyr - bias, body frame, dt from the timestamps):
//   q_{k+1} = Phi q_k,  Phi = exp(0.5 Omega(w) dt) = cos(|w|dt/2) I + sin(|w|dt/2)/|w| Omega(w)
//   (exact: Omega(w)^2 = -|w|^2 I), i.e. q_{k+1} = q_k (x) [cos(|w|dt/2), sin(|w|dt/2) w/|w|];
//   P = Phi P Phi^T + Q,  Q = (gyro_noise_rad_s dt / 2)^2 (I - q q^T)
//   (rate noise n gives dq = dt/2 Xi(q) n and Xi Xi^T = I - q q^T for a unit q).
// Measurement: z = the observed quaternion of eq. 1 with the sign of eq. 2, H = I,
//   R = (observation_noise_rad / 2)^2 I (a small rotation of angle a moves a unit quaternion by
//   about a/2); K = P (P + R)^-1, q += K (z - q), P = (I - K) P, then q is renormalised.
// A sample without a usable observation (NaN magnetometer = no reading, zero acceleration,
// field along gravity) is a prediction-only step.
//
// Per sample: fixed-size Eigen arithmetic only, no heap allocation.
#include <cstdint>
#include <vector>

#include "imu/gyro_bias_tracker.hpp"
#include "imu/imu_sample.hpp"
#include "imu/vector_observation.hpp"

namespace posefuse::imu {

using Vec4 = Eigen::Vector4d;
using Mat4 = Eigen::Matrix4d;

// Phi = exp(0.5 Omega(rate) dt) acting on [w x y z] (the prediction of II-D; exposed for tests).
Mat4 quaternion_transition_matrix(const Vec3& rate_rad_s, double dt_s);

class KalmanOrientationFilter {
 public:
  struct Params {
    // Std. dev. of the error of one bias-corrected gyro sample, rad/s: white noise plus what the
    // bias tracker has not removed. 0.01 rad/s (0.6 deg/s) covers a consumer MEMS gyro
    // (~0.1 deg/s noise at 80 Hz) with a residual bias of a fraction of a deg/s.
    double gyro_noise_rad_s = 0.01;
    // Std. dev. of the observed orientation angle, rad. Dominated by linear acceleration of the
    // arm tilting the observed "up" (the paper's filter does not gate it) and by residual
    // magnetic disturbance; 0.05 rad (~3 deg). With the gyro noise above the steady-state
    // gain is ~sqrt(Q/R) ~ 0.25% per sample at 80 Hz: a correction time constant of ~5 s.
    double observation_noise_rad = 0.05;
    // Std. dev. of the initial orientation (from the first sample's observation), rad.
    double initial_angle_sigma_rad = 0.1;
    // A gap between samples longer than this is not integrated (one gyro sample says nothing
    // about a long dropout); the covariance is reset to the initial one instead so that the next
    // observation takes over.
    double max_prediction_dt_s = 0.5;
    bool track_gyro_bias = true;  // false: use gyro_bias.initial_bias_rad_s throughout
    GyroBiasTracker::Params gyro_bias;
    ObservationLimits observation_limits;
  };

  KalmanOrientationFilter() : KalmanOrientationFilter(Params{}) {}
  // Throws posefuse::Error (kInvalidArgument) naming the bad parameter.
  explicit KalmanOrientationFilter(const Params& params);

  // Feeds one sample and returns W_from_A after it. The first sample initialises the filter from
  // its vector observation; if it has none, throws posefuse::Error (kFailedPrecondition, field
  // "imu[0].mag_uT" or "imu[0].acc_m_s2"). Non-finite gyro/acc or a timestamp not after the
  // previous one: posefuse::Error (kInvalidArgument) naming the sample and field; the filter
  // state is unchanged then.
  Quat update(const ImuSample& sample);

  // Resets the filter, validates the whole stream (validate_imu_stream) and runs it; one
  // W_from_A per sample.
  std::vector<Quat> process(const std::vector<ImuSample>& samples);

  void reset();
  bool initialised() const { return initialised_; }
  Quat W_from_A() const { return Quat(q_[0], q_[1], q_[2], q_[3]); }
  const Mat4& covariance() const { return P_; }
  const Vec3& gyro_bias_rad_s() const { return bias_tracker_.bias_rad_s(); }
  const Params& params() const { return params_; }

 private:
  Quat step(const ImuSample& sample);  // update() without the input checks
  void initialise(const ImuSample& sample);
  void predict(const Vec3& rate_rad_s, double dt_s);
  void correct(const Vec4& observed);

  Params params_;
  GyroBiasTracker bias_tracker_;
  double initial_variance_;
  double observation_variance_;
  bool initialised_ = false;
  std::int64_t last_t_us_ = 0;
  std::size_t sample_index_ = 0;
  Vec4 q_ = Vec4(1, 0, 0, 0);  // W_from_A, [w x y z]
  Mat4 P_ = Mat4::Identity();
};

}  // namespace posefuse::imu
