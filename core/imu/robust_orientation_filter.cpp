#include "imu/robust_orientation_filter.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "common/error.hpp"
#include "imu/lowpass_gain.hpp"

namespace posefuse::imu {

namespace {

// Brings a quaternion that is already almost unit back to unit length (first-order Newton step
// on |q| = 1, no square root; the per-step rounding drift is ~1e-16).
void renormalize(Quat& q) { q.coeffs() *= 0.5 * (3.0 - q.squaredNorm()); }

// Time constant of the candidate-field averages: only needs to smooth sensor noise.
constexpr double kCandidateTau_s = 1.0;

// The earth's rotation rate (sidereal day): what a gyro at rest still senses.
constexpr double kEarthRate_rad_s = 7.2921e-5;

// A step longer than this many nominal steps lost at least one sample.
constexpr double kGapSteps = 2.0;
// How long the fastest recent turn bounds what a gap may hide: a movement's peak speed recurs
// within about a second.
constexpr double kPeakRateMemory_s = 1.0;
// A body-worn IMU's distance from the joint that turns it (a wrist sensor from the elbow).
constexpr double kLeverArm_m = 0.3;
// Standard gravity: what a still accelerometer reads.
constexpr double kGravity_m_s2 = 9.80665;

// Rotates v by the unit quaternion q without building a matrix (v' = v + 2 w (u x v) + 2 u x (u x v)).
Vec3 rotate(const Quat& q, const Vec3& v) {
  const Vec3 u(q.x(), q.y(), q.z());
  const Vec3 t = 2.0 * u.cross(v);
  return v + q.w() * t + u.cross(t);
}

// cos and sin of a half angle; a short series when small (the per-sample case) to stay cheap.
void half_angle_cos_sin(double angle_rad, double& c, double& s) {
  const double h = 0.5 * angle_rad;
  if (std::abs(h) < 0.05) {
    const double h2 = h * h;
    c = 1.0 - h2 * (0.5 - h2 / 24.0);
    s = h * (1.0 - h2 * (1.0 / 6.0 - h2 / 120.0));
  } else {
    c = std::cos(h);
    s = std::sin(h);
  }
}

}  // namespace

RobustOrientationFilter::RobustOrientationFilter() : RobustOrientationFilter(Params{}) {}

RobustOrientationFilter::RobustOrientationFilter(const Params& params) : params_(params) {
  const auto positive = [](double v, const char* name) {
    if (!(v > 0.0) || !std::isfinite(v)) {
      throw_invalid(std::string("RobustOrientationFilter::Params::") + name,
                    "is " + std::to_string(v) + ", must be finite and > 0");
    }
  };
  positive(params.tau_acc_s, "tau_acc_s");
  positive(params.tau_mag_s, "tau_mag_s");
  positive(params.rest_tau_s, "rest_tau_s");
  positive(params.rest_min_s, "rest_min_s");
  positive(params.rest_gyr_threshold_rad_s, "rest_gyr_threshold_rad_s");
  positive(params.bias_sigma_init_rad_s, "bias_sigma_init_rad_s");
  positive(params.bias_drift_rad_s_per_sqrt_s, "bias_drift_rad_s_per_sqrt_s");
  positive(params.bias_motion_tau_s, "bias_motion_tau_s");
  positive(params.bias_limit_rad_s, "bias_limit_rad_s");
  positive(params.mag_norm_threshold, "mag_norm_threshold");
  positive(params.mag_dip_threshold_rad, "mag_dip_threshold_rad");
  positive(params.mag_ref_tau_s, "mag_ref_tau_s");
  positive(params.mag_new_field_s, "mag_new_field_s");
  positive(params.mag_new_field_min_gyr_rad_s, "mag_new_field_min_gyr_rad_s");
  positive(params.mag_hard_iron_tau_s, "mag_hard_iron_tau_s");
  positive(params.mag_hard_iron_min_excitation, "mag_hard_iron_min_excitation");
  positive(params.mag_hard_iron_max_rms, "mag_hard_iron_max_rms");
  positive(params.mag_accept_after_s, "mag_accept_after_s");
  positive(params.mag_hard_iron_min_s, "mag_hard_iron_min_s");
  positive(params.mag_hard_iron_return_s, "mag_hard_iron_return_s");
  positive(params.mag_recover_tau_s, "mag_recover_tau_s");
  positive(params.mag_recover_s, "mag_recover_s");
  positive(params.init_s, "init_s");
  bias_var_ = params.bias_sigma_init_rad_s * params.bias_sigma_init_rad_s;
}

void RobustOrientationFilter::reset_keeping_calibration(bool flip_gyro) {
  const Vec3 bias = bias_;
  const double bias_var = bias_var_;
  const Vec3 hard_iron = hard_iron_uT_;
  *this = RobustOrientationFilter(params_);
  bias_ = flip_gyro ? Vec3(-bias) : bias;
  bias_var_ = bias_var;
  hard_iron_uT_ = hard_iron;
}

std::vector<Quat> RobustOrientationFilter::process(const std::vector<ImuSample>& samples) {
  validate_imu_stream(samples, "imu");
  std::vector<Quat> out;
  out.reserve(samples.size());
  for (const ImuSample& s : samples) out.push_back(update(s));
  return out;
}

Quat RobustOrientationFilter::update(const ImuSample& s) {
  if (!s.gyr_rad_s.allFinite()) throw_invalid("imu.gyr_rad_s", "not finite at t_us " + std::to_string(s.t_us));
  if (!s.acc_m_s2.allFinite()) throw_invalid("imu.acc_m_s2", "not finite at t_us " + std::to_string(s.t_us));
  double dt_s = 0.0;
  if (started_) {
    if (s.t_us <= last_t_us_) {
      throw_invalid("imu.t_us", "timestamp " + std::to_string(s.t_us) + " is not after the previous one (" +
                                    std::to_string(last_t_us_) + ")");
    }
    dt_s = 1e-6 * static_cast<double>(s.t_us - last_t_us_);
    if (s.t_us - last_t_us_ != gains_.dt_us) update_gains(s.t_us - last_t_us_);
  }
  last_t_us_ = s.t_us;

  if (!started_) {
    // First sample: level the estimate at once, no integration step.
    started_ = true;
    acc_lp1_I_ = s.acc_m_s2;
    acc_lp_I_ = s.acc_m_s2;
    gyr_lp_ = s.gyr_rad_s;
    init_weight_count_ = 1.0;
    correct_inclination(s.acc_m_s2, 0.0);
  } else {
    time_s_ += dt_s;
    init_weight_count_ += 1.0;
    integrate_step(s.gyr_rad_s, dt_s);
    update_rest_detection(s, dt_s);
    correct_inclination(s.acc_m_s2, dt_s);
  }

  const Quat E_from_A_q = E_from_I_ * I_from_A_;
  E_from_A_m_ = E_from_A_q.toRotationMatrix();
  if (s.mag_uT.allFinite()) correct_heading(s.mag_uT, E_from_A_q, dt_s, (s.gyr_rad_s - bias_).squaredNorm());
  if (dt_s > 0.0) {
    E_from_A_lp1_acc_ += gains_.acc_stage * (E_from_A_m_ - E_from_A_lp1_acc_);
    E_from_A_lp_acc_ += gains_.acc_stage * (E_from_A_lp1_acc_ - E_from_A_lp_acc_);
  }
  if (dt_s > 0.0 && time_s_ > params_.init_s) {
    update_rest_bias(dt_s);
    // A correction that recovers from lost samples says nothing about the bias.
    if (!at_rest() && !inclination_.recovering) {
      // Motion: the corrections the accelerometer keeps making about the horizontal axes are
      // the drift a residual bias causes: e_E ~ -correction / dt. They answer the drift through
      // the tau_acc_s low-pass, so the drift is compared with the bias error seen through an
      // equally low-passed rotation: e_E ~ lowpass(E_from_A) * e_A. Fast turning shrinks the
      // low-passed rotation and with it the update, where the lagging corrections say little
      // about a sensor-frame bias. The magnetometer is deliberately not used here: through the
      // bias it could tilt the estimate, and it must only ever touch the heading.
      const Eigen::Vector2d e_horizontal(-acc_correction_rate_E_.x(), -acc_correction_rate_E_.y());
      bias_ += gains_.bias_motion * (E_from_A_lp_acc_.topRows<2>().transpose() * e_horizontal);
      const double limit = params_.bias_limit_rad_s;
      bias_ = bias_.cwiseMax(Vec3::Constant(-limit)).cwiseMin(Vec3::Constant(limit));
    }
  }

  const Quat W_from_E(heading_qw_, 0.0, 0.0, heading_qz_);
  return W_from_E * E_from_A_q;
}

void RobustOrientationFilter::update_gains(std::int64_t dt_us) {
  const double dt_s = 1e-6 * static_cast<double>(dt_us);
  gains_.dt_us = dt_us;
  gains_.inv_dt = 1.0 / dt_s;
  gains_.rest = lowpass_gain(dt_s, params_.rest_tau_s);
  gains_.acc_stage = lowpass_gain(dt_s, 0.5 * params_.tau_acc_s);
  gains_.mag = lowpass_gain(dt_s, params_.tau_mag_s);
  gains_.mag_ref = lowpass_gain(dt_s, params_.mag_ref_tau_s);
  gains_.mag_recover = lowpass_gain(dt_s, params_.mag_recover_tau_s);
  gains_.candidate = lowpass_gain(dt_s, kCandidateTau_s);
  gains_.hard_iron = lowpass_gain(dt_s, params_.mag_hard_iron_tau_s);
  gains_.bias_motion = lowpass_gain(dt_s, params_.bias_motion_tau_s);
}

void RobustOrientationFilter::integrate_step(const Vec3& gyr_rad_s, double dt_s) {
  const Vec3 rate = gyr_rad_s - bias_;
  const bool gap = nominal_dt_s_ > 0.0 && dt_s > kGapSteps * nominal_dt_s_;
  if (!gap) {
    // The nominal step follows the steps that lost nothing; a first step that was a gap is
    // replaced as soon as a regular one comes.
    nominal_dt_s_ = (nominal_dt_s_ == 0.0 || dt_s < nominal_dt_s_ / kGapSteps)
                        ? dt_s
                        : nominal_dt_s_ + 0.1 * (dt_s - nominal_dt_s_);
    integrate_gyro(rate, dt_s);
  } else {
    // The rates at the gap's ends bridge it (exact for a rate that changes linearly). A rate
    // whose change is bounded by the fastest recent angular acceleration strays from that
    // bridge by at most a quarter of it times the step squared; no turn exceeds the fastest
    // recent rate over the missing time. The smaller bound is the error, in any direction:
    // two thirds of its variance tilt, one third heading.
    const double lost_s = dt_s - nominal_dt_s_;
    ++gaps_;
    lost_s_ += lost_s;
    const double acceleration = std::max(peak_acceleration_rad_s2_, (rate - last_rate_rad_s_).norm() / dt_s);
    const double turn_rad = std::min(3.14159265358979, std::max(rate.norm(), peak_rate_rad_s_) * lost_s);
    const double bridge_rad = std::min(turn_rad, 0.25 * acceleration * dt_s * dt_s);
    const double turn_var = turn_rad * turn_rad, bridge_var = bridge_rad * bridge_rad;
    inclination_.add_gap(bridge_var * (2.0 / 3.0), turn_var * (2.0 / 3.0));
    heading_.add_gap(bridge_var / 3.0, turn_var / 3.0);
    integrate_gyro(0.5 * (rate + last_rate_rad_s_), dt_s);
  }
  // The fastest turn and the fastest change of turn of the last second or so: what may have
  // happened unseen in a gap.
  const double decay = 1.0 - std::min(1.0, dt_s / kPeakRateMemory_s);
  peak_rate_rad_s_ = std::max(rate.norm(), peak_rate_rad_s_ * decay);
  if (!gap)
    peak_acceleration_rad_s2_ = std::max((rate - last_rate_rad_s_).norm() / dt_s, peak_acceleration_rad_s2_ * decay);
  last_rate_rad_s_ = rate;
}

void RobustOrientationFilter::integrate_gyro(const Vec3& rate_rad_s, double dt_s) {
  // Exponential map of the bias-corrected rate over one step, as a short series (|w| dt << 1
  // at IMU rates; the 4th-order terms keep it exact to ~1e-12 up to 0.1 rad per step).
  const Vec3 h = 0.5 * dt_s * rate_rad_s;
  const double h2 = h.squaredNorm();
  double c, s;
  if (h2 < 0.0025) {
    c = 1.0 - h2 * (0.5 - h2 / 24.0);
    s = 1.0 - h2 * (1.0 / 6.0 - h2 / 120.0);
  } else {
    const double a = std::sqrt(h2);
    c = std::cos(a);
    s = std::sin(a) / a;
  }
  const Quat step(c, s * h.x(), s * h.y(), s * h.z());
  I_from_A_ = I_from_A_ * step;
  renormalize(I_from_A_);
}

void RobustOrientationFilter::update_rest_detection(const ImuSample& s, double dt_s) {
  gyr_lp_ += gains_.rest * (s.gyr_rad_s - gyr_lp_);
  const double gyr_th = params_.rest_gyr_threshold_rad_s;
  // Besides being steady, the rate must be small in absolute terms: a slow constant turn about
  // the vertical is steady too, but no bias is that large.
  const bool steady = (s.gyr_rad_s - gyr_lp_).squaredNorm() < gyr_th * gyr_th &&
                      gyr_lp_.squaredNorm() < params_.bias_limit_rad_s * params_.bias_limit_rad_s;
  if (!steady) {
    rest_s_ = 0.0;
    return;
  }
  if (rest_s_ == 0.0) {
    // A steady stretch begins: what the bias filter knew before it is the prior for the rest
    // measurement, which is the plain mean of the raw gyro over the whole stretch.
    rest_prior_bias_ = bias_;
    rest_prior_var_ = bias_var_;
    rest_gyr_sum_.setZero();
    rest_gyr_sq_sum_ = 0.0;
    rest_count_ = 0.0;
  }
  rest_s_ += dt_s;
  rest_gyr_sum_ += s.gyr_rad_s;
  rest_gyr_sq_sum_ += s.gyr_rad_s.squaredNorm();
  rest_count_ += 1.0;
}

void RobustOrientationFilter::update_rest_bias(double dt_s) {
  const double drift = params_.bias_drift_rad_s_per_sqrt_s;
  bias_var_ += drift * drift * dt_s;
  if (!at_rest()) return;
  // At rest the mean gyro over the steady stretch measures the bias; its variance per axis is
  // the stretch's own sample variance over the count, floored at the earth's rotation rate
  // squared (a still gyro senses that rotation too, so no rest measurement is better). One
  // Kalman update of the prior from the stretch's start, per axis alike.
  const double n = rest_count_;
  const Vec3 mean = rest_gyr_sum_ / n;
  const double sample_var = std::max(0.0, rest_gyr_sq_sum_ / n - mean.squaredNorm()) / 3.0;
  const double r = std::max(sample_var / n, kEarthRate_rad_s * kEarthRate_rad_s);
  double prior_var = rest_prior_var_;
  // A bias that stepped while the sensor moved (temperature, a power cycle) shows as a rest
  // mean far outside what the prior and the measurement allow together: 3 sigma over the 3
  // axes (chi-square, 3 degrees of freedom, 99.7 %: 14.2). Then the prior is widened to the
  // step, so the rest measurement takes over at once instead of being averaged in slowly.
  const double d2 = (mean - rest_prior_bias_).squaredNorm();
  if (d2 > 14.2 * (prior_var + r)) prior_var = std::max(prior_var, d2 / 3.0);
  const double gain = prior_var / (prior_var + r);
  bias_ = rest_prior_bias_ + gain * (mean - rest_prior_bias_);
  bias_var_ = prior_var * (1.0 - gain);
}

void RobustOrientationFilter::correct_inclination(const Vec3& acc_m_s2, double dt_s) {
  // Low-pass in the almost-inertial frame I: accelerations while the sensor moves and turns
  // average out there, gravity does not.
  // Two first-order stages of tau_acc_s / 2 each: -40 dB/decade, so at the default 4 s a 1 Hz
  // back-and-forth movement is damped ~160x, where one 4 s stage would damp it only ~25x.
  // The time constant's gain; a sample without a step in time, and the start-up's equal-weight
  // averaging, take more (min_gain), which steady tracking would not.
  const double tau_gain = dt_s > 0.0 ? gains_.acc_stage : 0.0;
  double min_gain = dt_s > 0.0 ? 0.0 : 1.0;
  if (in_start_up()) min_gain = std::max(min_gain, 1.0 / init_weight_count_);
  double k = std::max(tau_gain, min_gain);
  const Vec3 acc_I = rotate(I_from_A_, acc_m_s2);
  const double acc_norm = acc_I.norm();
  if (acc_norm > 1e-9) {
    // This sample's tilt from the current vertical (its horizontal part, ~ the angle): its
    // variance is the estimate's plus one sample's scatter, which is what is learned.
    const Vec3 up_E = rotate(E_from_I_, acc_I) * (1.0 / acc_norm);
    // A sample whose norm is off gravity's by d carries an acceleration of at least d, and a
    // sensor kLeverArm_m from the joint that turns it at w with angular acceleration a one of
    // about (w^2 + a) kLeverArm_m, whatever its norm: each may tilt it by up to asin(acc / g).
    const double turning_acc = (last_rate_rad_s_.squaredNorm() + peak_acceleration_rad_s2_) * kLeverArm_m;
    const double off_g = std::min(1.0, std::max(std::abs(acc_norm - kGravity_m_s2), turning_acc) / kGravity_m_s2);
    const double prior_var = inclination_.gain_var_rad2;
    const bool was_recovering = inclination_.recovering;
    const double off_g_rad = std::asin(off_g);
    // These accelerations last as long as the learned disturbances do.
    k = inclination_.correct(tau_gain, min_gain, acc_scatter_.sample_var_rad2(dt_s, off_g_rad * off_g_rad), 0.0, true,
                             Eigen::Vector2d(up_E.x(), up_E.y()));
    // The scatter is learned only while tracking after start-up: during a recovery the
    // estimate's own error would pass for the accelerometer's.
    if (!was_recovering && dt_s > 0.0 && !in_start_up()) {
      acc_scatter_.learn(Eigen::Vector2d(up_E.x(), up_E.y()), prior_var, dt_s);
    }
  }
  acc_lp1_I_ += k * (acc_I - acc_lp1_I_);
  // During a recovery the vertical is the weighted mean the uncertainty describes (one stage);
  // the second stage would keep weight on what the lost samples made wrong.
  if (inclination_.recovering) {
    acc_lp_I_ = acc_lp1_I_;
  } else {
    acc_lp_I_ += k * (acc_lp1_I_ - acc_lp_I_);
  }

  // Rotate E_from_I so that the filtered vector becomes vertical: the smallest rotation taking
  // a = normalised E_from_I * acc_lp_I to +z, quaternion [w, a_y / 2w, -a_x / 2w, 0] with
  // w = sqrt((1 + a_z) / 2).
  const double norm = acc_lp_I_.norm();
  acc_correction_rate_E_.setZero();
  if (norm < 1e-9) return;
  const Vec3 a = rotate(E_from_I_, acc_lp_I_) * (1.0 / norm);
  Quat correction;
  const double w = std::sqrt(std::max(0.0, 0.5 * (1.0 + a.z())));
  if (w < 1e-6) {
    correction = Quat(0.0, 1.0, 0.0, 0.0);  // upside down: turn half-way about x
  } else {
    const double inv_w = 1.0 / w;
    correction = Quat(w, 0.5 * inv_w * a.y(), -0.5 * inv_w * a.x(), 0.0);
    if (dt_s > 0.0) acc_correction_rate_E_ = Vec3(a.y(), -a.x(), 0.0) * (inv_w * gains_.inv_dt);
  }
  E_from_I_ = correction * E_from_I_;
  renormalize(E_from_I_);
}

bool RobustOrientationFilter::fits_field(double norm_uT, double sin_dip, double ref_norm_uT, double ref_sin_dip) const {
  // |norm - ref| < threshold * ref and |dip - ref dip| < threshold, the latter to first order
  // in sin(dip): |sin dip - sin ref| < threshold * cos(ref). Squared, to avoid square roots.
  const double d_norm = norm_uT - ref_norm_uT;
  const double d_sin = sin_dip - ref_sin_dip;
  const double max_norm = params_.mag_norm_threshold * ref_norm_uT;
  const double max_dip = params_.mag_dip_threshold_rad;
  return d_norm * d_norm < max_norm * max_norm && d_sin * d_sin < max_dip * max_dip * (1.0 - ref_sin_dip * ref_sin_dip);
}

bool RobustOrientationFilter::heading_error(const Vec3& m_E, double& error_rad) const {
  // The angle that turns the horizontal field, seen through Rz(heading), onto +x (magnetic
  // north). Rz(heading) as a 2D rotation: cos = w^2 - z^2, sin = 2 w z.
  const double hc = heading_qw_ * heading_qw_ - heading_qz_ * heading_qz_;
  const double hs = 2.0 * heading_qw_ * heading_qz_;
  const double north = hc * m_E.x() - hs * m_E.y();
  const double west = hs * m_E.x() + hc * m_E.y();
  if (north * north + west * west < 1e-12) return false;
  if (north > 0.0 && std::abs(west) < 0.2 * north) {
    // Small error (the usual case): atan series, |x| < 0.2 keeps it within 1e-7 rad.
    const double x = west / north, x2 = x * x;
    error_rad = -x * (1.0 - x2 * (1.0 / 3.0 - x2 * (1.0 / 5.0 - x2 / 7.0)));
  } else {
    error_rad = -std::atan2(west, north);
  }
  return true;
}

void RobustOrientationFilter::correct_heading(const Vec3& mag_uT, const Quat& E_from_A, double dt_s,
                                              double gyr_sq_rad2_s2) {
  const Vec3 m_E = rotate(E_from_A, mag_uT - hard_iron_uT_);
  const double norm = m_E.norm();
  if (norm < 1e-6) return;
  const double sin_dip = -m_E.z() / norm;  // positive when the field points down

  // As for the inclination: the time constant's gain, and what a start-up or a fast pull takes.
  const double tau_gain = dt_s > 0.0 ? gains_.mag : 0.0;
  double min_gain = dt_s > 0.0 ? 0.0 : 1.0;
  if (in_start_up() && !mag_ref_valid_) {
    // Start-up: learn the reference as the plain mean and converge the heading fast.
    mag_init_count_ += 1.0;
    mag_ref_norm_ += (norm - mag_ref_norm_) / mag_init_count_;
    mag_ref_sin_dip_ += (sin_dip - mag_ref_sin_dip_) / mag_init_count_;
    min_gain = std::max(min_gain, 1.0 / mag_init_count_);
    mag_disturbed_ = false;
  } else {
    mag_ref_valid_ = true;
    // Once disturbed, the field must fit the reference for mag_accept_after_s before it is
    // trusted again: a wrong field passes the test by chance in some orientations.
    if (!fits_reference(norm, sin_dip)) {
      if (!mag_disturbed_) reset_hard_iron_fit();
      mag_disturbed_ = true;
      mag_clean_s_ = 0.0;
    } else {
      mag_clean_s_ += dt_s;
      if (mag_clean_s_ >= params_.mag_accept_after_s) mag_disturbed_ = false;
    }
    if (mag_disturbed_) {
      // The magnet may have been taken off again: does the field fit with the previous offset?
      if (check_previous_hard_iron(mag_uT, E_from_A, dt_s)) return;
      // Track a candidate new field and a candidate hard iron; use neither for heading yet.
      if (cand_valid_ && fits_field(norm, sin_dip, cand_norm_, cand_sin_dip_)) {
        const double kc = gains_.candidate;
        cand_norm_ += kc * (norm - cand_norm_);
        cand_sin_dip_ += kc * (sin_dip - cand_sin_dip_);
        const double min_gyr = params_.mag_new_field_min_gyr_rad_s;
        if (gyr_sq_rad2_s2 > min_gyr * min_gyr) cand_s_ += dt_s;
      } else {
        cand_valid_ = true;
        cand_norm_ = norm;
        cand_sin_dip_ = sin_dip;
        cand_s_ = 0.0;
      }
      update_hard_iron_fit(mag_uT, dt_s);
      if (cand_s_ >= params_.mag_new_field_s) {
        mag_ref_norm_ = cand_norm_;
        mag_ref_sin_dip_ = cand_sin_dip_;
        cand_valid_ = false;
        mag_recover_left_s_ = params_.mag_recover_s;
      }
      return;
    }
    cand_valid_ = false;
    // Undisturbed samples refine the offset too: a residual of the prior calibration, or a
    // magnet too weak to fail the norm and dip test, shows as a better-fitting offset.
    update_hard_iron_fit(mag_uT, dt_s);
    // Undisturbed: the reference follows slowly (sensor warm-up, slow changes of place).
    const double kr = gains_.mag_ref;
    mag_ref_norm_ += kr * (norm - mag_ref_norm_);
    mag_ref_sin_dip_ += kr * (sin_dip - mag_ref_sin_dip_);
    if (mag_recover_left_s_ > 0.0) {
      min_gain = std::max(min_gain, gains_.mag_recover);
      mag_recover_left_s_ -= dt_s;
    }
  }

  double error_rad = 0.0;
  if (!heading_error(m_E, error_rad)) return;  // field vertical: no heading information
  // As for the inclination: this sample's heading error has the estimate's variance plus one
  // sample's scatter; the gain is the larger of the time constant's and the uncertainty's.
  const double prior_var = heading_.gain_var_rad2;
  const bool was_recovering = heading_.recovering;
  // An inclination error of d turns the horizontal field by up to d tan(dip): while the
  // inclination is uncertain, so is every sample's heading.
  const double tan2_dip = this->tan2_dip();
  // The inclination's uncertainty reaches every sample's heading alike; at start-up both are
  // averaged from the same first samples and converge together.
  const double tilt_var = in_start_up() ? 0.0 : inclination_.gain_var_rad2 * tan2_dip;
  const double k = heading_.correct(tau_gain, min_gain, mag_scatter_.sample_var_rad2(dt_s), tilt_var,
                                    !inclination_.recovering, Eigen::Vector2d(error_rad, 0.0));
  // The inclination's error turns every sample's heading alike, so averaging does not shrink
  // it: the heading stays at least as uncertain as the inclination's excess makes it.
  const double tilt_excess_var = inclination_.excess_var_rad2() * tan2_dip;
  heading_.reported_var_rad2 =
      std::min(CorrectionUncertainty::kUnknownVarRad2,
               std::max(heading_.reported_var_rad2, heading_.steady_var_rad2 + tilt_excess_var));
  if (!was_recovering && dt_s > 0.0 && !in_start_up()) {
    mag_scatter_.learn(Eigen::Vector2d(error_rad, 0.0), prior_var, dt_s);
  }
  const double step_rad = k * error_rad;
  double c, s;
  half_angle_cos_sin(step_rad, c, s);
  const double qw = c * heading_qw_ - s * heading_qz_;
  const double qz = c * heading_qz_ + s * heading_qw_;
  const double renorm = 0.5 * (3.0 - (qw * qw + qz * qz));  // as renormalize()
  heading_qw_ = qw * renorm;
  heading_qz_ = qz * renorm;
}

void RobustOrientationFilter::update_hard_iron_fit(const Vec3& mag_uT, double dt_s) {
  // Model of a sensor-fixed offset: m_A = A_from_E * b_E + h_A, with b_E the (constant) field in
  // E. Linear in x = [b_E; h_A] with J = [A_from_E, I], so J^T J = [I, E_from_A; A_from_E, I]:
  // the normal equations need only the forgetting sums of A_from_E, of m_E = E_from_A m, of m
  // and of |m|^2 (a few dozen flops per sample; the 6x6 system is formed at the checks).
  const double forget = 1.0 - gains_.hard_iron;
  hi_A_from_E_sum_ = forget * hi_A_from_E_sum_ + E_from_A_m_.transpose();
  hi_m_E_sum_ = forget * hi_m_E_sum_ + E_from_A_m_ * mag_uT;
  hi_m_A_sum_ = forget * hi_m_A_sum_ + mag_uT;
  hi_sum_sq_ = forget * hi_sum_sq_ + mag_uT.squaredNorm();
  hi_weight_ = forget * hi_weight_ + 1.0;
  hi_check_s_ += dt_s;
  hi_duration_s_ += dt_s;
  if (hi_check_s_ < 0.5 || hi_duration_s_ < params_.mag_hard_iron_min_s) return;
  hi_check_s_ = 0.0;

  Eigen::Matrix<double, 6, 6> normal;
  normal << hi_weight_ * Eigen::Matrix3d::Identity(), hi_A_from_E_sum_.transpose(), hi_A_from_E_sum_,
      hi_weight_ * Eigen::Matrix3d::Identity();
  Eigen::Matrix<double, 6, 1> rhs;
  rhs << hi_m_E_sum_, hi_m_A_sum_;
  // Excitation: all six directions must be seen; the smallest eigenvalue of the averaged normal
  // matrix is 0 without rotation and up to 1 (per sample) with rotations spread evenly.
  const Eigen::Matrix<double, 6, 6> averaged = normal / hi_weight_;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(averaged, Eigen::EigenvaluesOnly);
  if (eig.eigenvalues()(0) < params_.mag_hard_iron_min_excitation) return;
  const Eigen::Matrix<double, 6, 1> x = normal.ldlt().solve(rhs);
  const Vec3 b_E = x.head<3>();
  const double norm = b_E.norm();
  if (!x.allFinite() || norm < 1e-6 || !fits_reference(norm, -b_E.z() / norm)) return;
  // RMS of |J x - m| over the (weighted) samples, from the accumulated sums.
  const auto rms_uT = [&](const Eigen::Matrix<double, 6, 1>& v) {
    const double residual_sq = hi_sum_sq_ - 2.0 * v.dot(rhs) + v.dot(normal * v);
    return std::sqrt(std::max(0.0, residual_sq) / (3.0 * hi_weight_));
  };
  // The best field for the current offset, for comparison: b = (r_b - sum(E_from_A) h) / W.
  Eigen::Matrix<double, 6, 1> x_current;
  x_current << (hi_m_E_sum_ - hi_A_from_E_sum_.transpose() * hard_iron_uT_) / hi_weight_, hard_iron_uT_;
  // Accept only a clear, well-explained offset: the fit must explain the samples (a field
  // disturbance that is not a sensor-fixed offset, a magnet beside the path, does not) and
  // halve the residual of the current offset (a change within the noise does not).
  const double rms_new = rms_uT(x);
  if (rms_new > params_.mag_hard_iron_max_rms * mag_ref_norm_ || rms_new > 0.5 * rms_uT(x_current)) return;
  if (mag_disturbed_) {
    hard_iron_prev_uT_ = hard_iron_uT_;  // a magnet attached: remember the offset without it
  } else if (hard_iron_prev_uT_ == hard_iron_uT_) {
    hard_iron_prev_uT_ = x.tail<3>();  // a refinement with no magnet episode open
  }
  hard_iron_uT_ = x.tail<3>();
  mag_ref_norm_ = norm;
  mag_ref_sin_dip_ = -b_E.z() / norm;
  if (mag_disturbed_) mag_recover_left_s_ = params_.mag_recover_s;
  reset_hard_iron_fit();
}

bool RobustOrientationFilter::check_previous_hard_iron(const Vec3& mag_uT, const Quat& E_from_A, double dt_s) {
  if (hard_iron_prev_uT_ == hard_iron_uT_) return false;
  const Vec3 m_E = rotate(E_from_A, mag_uT - hard_iron_prev_uT_);
  const double norm = m_E.norm();
  if (norm < 1e-6 || !fits_reference(norm, -m_E.z() / norm)) {
    prev_fit_s_ = 0.0;
    return false;
  }
  prev_fit_s_ += dt_s;
  if (prev_fit_s_ < params_.mag_hard_iron_return_s) return false;
  std::swap(hard_iron_uT_, hard_iron_prev_uT_);
  prev_fit_s_ = 0.0;
  mag_clean_s_ = params_.mag_accept_after_s;  // this field has just fitted for a while
  mag_disturbed_ = false;
  mag_recover_left_s_ = params_.mag_recover_s;
  reset_hard_iron_fit();
  return true;
}

void RobustOrientationFilter::reset_hard_iron_fit() {
  hi_A_from_E_sum_.setZero();
  hi_m_E_sum_.setZero();
  hi_m_A_sum_.setZero();
  hi_weight_ = 0.0;
  hi_sum_sq_ = 0.0;
  hi_check_s_ = 0.0;
  hi_duration_s_ = 0.0;
}

}  // namespace posefuse::imu
