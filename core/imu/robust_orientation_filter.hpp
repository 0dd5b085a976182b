#pragma once
// Robust 9-axis orientation filter (beyond paper 1, II-D): separate inclination and heading
// corrections in the spirit of VQF (Laidig & Seel 2023), written for posefuse.
//
// The orientation is kept as three factors, W_from_A = Rz(heading) * E_from_I * I_from_A:
//  - I_from_A: strapdown integration of the bias-corrected gyroscope ("I" is an almost-inertial
//    frame that drifts slowly with the residual gyro bias);
//  - E_from_I: inclination correction. The accelerometer is rotated into I and low-pass filtered
//    there, so short accelerations, taps and vibration average out while the sensor turns; the
//    correction rotates the filtered vector onto the vertical (rotation about a horizontal axis);
//  - Rz(heading): heading correction about the vertical from the magnetometer, so a bad magnetic
//    field can never tilt the estimate.
// Gyro bias: a small Kalman filter, fed by the low-passed gyro during detected rest (accurate)
// and, slowly, by the corrections the accelerometer and magnetometer make during motion.
// Magnetic disturbances: the field's norm and dip are compared with a reference learned online;
// a disturbed sample is not used. A new field that stays consistent while the sensor rotates is
// adopted after a while (moving to another room); the sensor-fixed offset (hard iron: what the
// prior calibration left, or a magnet attached to the sensor) is estimated all the time by least
// squares from the rotation, and a clearly better offset replaces the current one.
// Lost samples: a step longer than two nominal steps is bridged with the mean of the rates at
// its ends, and the rotation it cannot know (bounded by the fastest recent angular acceleration
// and rate) is
// added to the orientation's uncertainty. Until it has shrunk back, the inclination and heading
// corrections take the gain a Kalman filter would give that uncertainty against one sample's
// (measured) error, when it is larger than the time constant's: after a gap the estimate snaps
// back to what the accelerometer and magnetometer say and then averages, as at start-up,
// instead of decaying over tau_mag_s. The uncertainty is reported per sample
// (orientation_uncertainty_rad).
// Details and parameter guidance: docs/imu-robust.md.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "imu/correction_uncertainty.hpp"
#include "imu/imu_sample.hpp"
#include "imu/innovation_scatter.hpp"

namespace posefuse::imu {

class RobustOrientationFilter {
 public:
  struct Params {
    // Inclination: time constant of the inertial-frame accelerometer low-pass. Longer averages
    // out longer accelerations but lets gyro-bias drift build up a larger tilt error.
    double tau_acc_s = 4.0;
    // Heading: time constant with which the magnetometer pulls the heading.
    double tau_mag_s = 20.0;

    // Rest detection (for the gyro bias, rest means "not rotating"): the gyro is low-passed with
    // rest_tau_s; the sensor is at rest when the gyro deviates from its low-pass by less than
    // the threshold for at least rest_min_s. The accelerometer is not asked: vibration and
    // translation do not turn the sensor, and the mean gyro still measures the bias then.
    double rest_tau_s = 0.5;
    double rest_min_s = 1.5;
    double rest_gyr_threshold_rad_s = 2.0 * 3.14159265358979 / 180.0;

    // Gyro bias Kalman filter (per axis, rad/s): initial uncertainty and random-walk drift of
    // the bias. A rest measurement (the mean gyro over a steady stretch) carries its own
    // variance, from the stretch's samples.
    double bias_sigma_init_rad_s = 0.5 * 3.14159265358979 / 180.0;
    double bias_drift_rad_s_per_sqrt_s = 0.002 * 3.14159265358979 / 180.0;
    // During motion the bias follows the rate of the accelerometer/magnetometer corrections
    // with this time constant (slow: those corrections are noisy and lag by ~tau_acc_s).
    double bias_motion_tau_s = 60.0;
    // Largest bias the filter will accept (rad/s); MEMS gyros are well inside this.
    double bias_limit_rad_s = 5.0 * 3.14159265358979 / 180.0;

    // Magnetic disturbance: a sample is undisturbed when its norm is within
    // mag_norm_threshold (fraction of the reference norm) and its dip angle within
    // mag_dip_threshold_rad of the reference. The reference follows undisturbed samples with
    // mag_ref_tau_s.
    double mag_norm_threshold = 0.1;
    double mag_dip_threshold_rad = 10.0 * 3.14159265358979 / 180.0;
    double mag_ref_tau_s = 30.0;
    // After a disturbance, the field must fit the reference this long before it is used again.
    double mag_accept_after_s = 0.5;
    // A disturbed but self-consistent new field (norm and dip steady) is adopted as the new
    // reference after mag_new_field_s of consistent samples while turning faster than
    // mag_new_field_min_gyr_rad_s (a sensor-fixed magnet would not stay consistent then).
    double mag_new_field_s = 10.0;
    double mag_new_field_min_gyr_rad_s = 20.0 * 3.14159265358979 / 180.0;
    // Hard-iron re-learning, always on: fit m_A = A_from_E * b_E + h_A by exponentially
    // forgetting least squares (time constant mag_hard_iron_tau_s; restarted when a disturbance
    // begins); accept h_A once the rotation excites all directions (smallest normalised
    // eigenvalue above mag_hard_iron_min_excitation), the fitted field b_E matches the reference,
    // the fit explains the samples (RMS residual below mag_hard_iron_max_rms times the reference
    // norm) and halves the RMS residual of the current offset, after at least
    // mag_hard_iron_min_s of samples.
    double mag_hard_iron_tau_s = 20.0;
    double mag_hard_iron_min_excitation = 0.05;
    double mag_hard_iron_max_rms = 0.05;
    double mag_hard_iron_min_s = 10.0;
    // The previous offset comes back (magnet taken off) once the field fits the reference
    // with it for mag_hard_iron_return_s without a break.
    double mag_hard_iron_return_s = 2.0;
    // After the magnetometer was rejected for a while, the heading may have drifted; the first
    // accepted samples pull with the faster time constant mag_recover_tau_s for
    // mag_recover_s.
    double mag_recover_tau_s = 2.0;
    double mag_recover_s = 2.0;

    // Start-up: for the first init_s seconds low-passes average with equal weights (fast
    // convergence from an unknown start) and magnetic rejection is off while the reference is
    // learned.
    double init_s = 1.0;
  };

  RobustOrientationFilter();
  explicit RobustOrientationFilter(const Params& params);

  // One sample; returns W_from_A (W: x magnetic north, y west, z up). Does not allocate.
  // Throws posefuse::Error for non-finite gyro/acc or a timestamp not after the previous one.
  Quat update(const ImuSample& sample);

  // Whole stream from the current state; validates it first (validate_imu_stream).
  std::vector<Quat> process(const std::vector<ImuSample>& samples);

  // Inspection (tests, diagnostics).
  const Params& params() const { return params_; }
  // The orientation before the heading correction: gyro integration with the inclination
  // correction, in a frame E whose heading drifts with the gyro (W_from_A = Rz * E_from_A).
  Quat E_from_A() const { return E_from_I_ * I_from_A_; }
  const Vec3& gyro_bias_rad_s() const { return bias_; }
  bool at_rest() const { return rest_s_ >= params_.rest_min_s; }
  bool mag_disturbed() const { return mag_disturbed_; }
  // Predicted RMS error of the last sample's inclination and heading (rad) beyond steady
  // tracking (whose error is measured on BROAD, docs/benchmarks.md): what start-up and lost
  // samples leave uncorrected, from the measured scatter of the accelerometer about the
  // vertical and of the magnetometer's heading; and at least the error the corrections keep
  // showing (their innovations low-passed over 2 s: the lag a gyro bias the filter has not
  // learned makes, tau_mag_s times the bias about the vertical, shows there).
  // During the start-up (init_s) the estimate is an equal-weight average of the first samples,
  // and how far a sample scatters is learned only after it: the error is not known yet, and both
  // are reported as unknown (pi/2 RMS each). A start in vigorous motion (a jumping jack) is 20
  // degrees off in heading there while its first samples agree with each other.
  double inclination_uncertainty_rad() const {
    if (in_start_up()) return std::sqrt(CorrectionUncertainty::kUnknownVarRad2);
    return std::max(std::sqrt(inclination_.excess_var_rad2()), acc_scatter_.persistent_rad());
  }
  // At least what the inclination's error turns the horizontal field by (up to d tan(dip)):
  // every sample's heading shares it, so no agreement of the samples can show it. That includes
  // the tilt the accelerometer keeps showing: an unlearned horizontal gyro bias holds the
  // inclination off, and the magnetometer, read through that inclination, then agrees with a
  // heading that is off too.
  double heading_uncertainty_rad() const {
    if (in_start_up()) return std::sqrt(CorrectionUncertainty::kUnknownVarRad2);
    const double tilt_rad = inclination_uncertainty_rad() * std::sqrt(tan2_dip());
    return std::max({std::sqrt(heading_.excess_var_rad2()), mag_scatter_.persistent_rad(), tilt_rad});
  }
  double orientation_uncertainty_rad() const {
    const double i = inclination_uncertainty_rad(), h = heading_uncertainty_rad();
    return std::sqrt(i * i + h * h);
  }
  // Steps that lost samples (longer than two nominal steps), and the time they lost.
  std::uint64_t gaps() const { return gaps_; }
  double lost_s() const { return lost_s_; }
  const Vec3& hard_iron_uT() const { return hard_iron_uT_; }
  double mag_ref_norm_uT() const { return mag_ref_norm_; }
  double mag_ref_dip_rad() const { return std::asin(mag_ref_sin_dip_); }

  // Starts a fresh run that keeps what the filter learned about the sensor itself (gyro bias
  // and its uncertainty, hard iron), e.g. for a second pass over a recording. The magnetic
  // reference is learned anew from the run's own start, as in the first run. With `flip_gyro`
  // the next run feeds the gyro negated (a time-reversed pass), so the bias flips too.
  void reset_keeping_calibration(bool flip_gyro = false);

 private:
  bool in_start_up() const { return time_s_ < params_.init_s; }
  // tan^2 of the reference field's dip (sin^2 capped at 0.99, 84 degrees): how much an
  // inclination error turns the horizontal field.
  double tan2_dip() const {
    const double sin2_dip = std::min(0.99, mag_ref_sin_dip_ * mag_ref_sin_dip_);
    return sin2_dip / (1.0 - sin2_dip);
  }
  void integrate_gyro(const Vec3& rate_rad_s, double dt_s);  // bias-corrected rate
  void update_rest_detection(const ImuSample& s, double dt_s);
  void correct_inclination(const Vec3& acc_m_s2, double dt_s);
  void correct_heading(const Vec3& mag_uT, const Quat& E_from_A, double dt_s, double gyr_sq_rad2_s2);
  void update_gains(std::int64_t dt_us);
  // Integrates the step; a step that lost samples is bridged and its unknown rotation joins
  // the uncertainty.
  void integrate_step(const Vec3& gyr_rad_s, double dt_s);
  void update_rest_bias(double dt_s);
  void update_hard_iron_fit(const Vec3& mag_uT, double dt_s);
  void reset_hard_iron_fit();
  // Switches back to the previous hard iron when the field fits with it again; returns whether it did.
  bool check_previous_hard_iron(const Vec3& mag_uT, const Quat& E_from_A, double dt_s);
  // The heading correction that turns m_E's horizontal part north; false when it has none.
  bool heading_error(const Vec3& m_E, double& error_rad) const;
  bool fits_field(double norm_uT, double sin_dip, double ref_norm_uT, double ref_sin_dip) const;
  bool fits_reference(double norm_uT, double sin_dip) const {
    return fits_field(norm_uT, sin_dip, mag_ref_norm_, mag_ref_sin_dip_);
  }

  Params params_;

  // Low-pass gains dt / (tau + dt) for the current step length, recomputed only when it changes.
  struct Gains {
    std::int64_t dt_us = -1;
    double inv_dt = 0;
    double rest = 0, acc_stage = 0, mag = 0, mag_ref = 0, mag_recover = 0, candidate = 0, hard_iron = 0,
           bias_motion = 0;
  };
  Gains gains_;

  // Orientation factors.
  Quat I_from_A_ = Quat::Identity();
  Quat E_from_I_ = Quat::Identity();
  double heading_qw_ = 1.0, heading_qz_ = 0.0;  // Rz(heading) as the quaternion (w, 0, 0, z)

  bool started_ = false;
  std::int64_t last_t_us_ = 0;
  double time_s_ = 0.0;
  double init_weight_count_ = 0.0;  // samples seen during start-up, for equal-weight averaging

  // Lost samples.
  double nominal_dt_s_ = 0.0;
  Vec3 last_rate_rad_s_ = Vec3::Zero();    // bias-corrected rate of the previous sample
  double peak_rate_rad_s_ = 0.0;           // the largest recent |rate|, decaying over a second
  double peak_acceleration_rad_s2_ = 0.0;  // the same for |d rate / dt|
  std::uint64_t gaps_ = 0;
  double lost_s_ = 0.0;
  // The inclination's and the heading's uncertainty (start-up: unknown).
  CorrectionUncertainty inclination_, heading_;
  // One sample's error, learned while tracking: the accelerometer's tilt from the vertical and
  // the magnetometer's heading error, beyond the estimate's own uncertainty.
  InnovationScatter acc_scatter_{kScatterTau_s, kMinSampleSigma_rad};
  InnovationScatter mag_scatter_{kScatterTau_s, kMinSampleSigma_rad};
  // Learning time of the scatter (and the longest correlation it tells); the sensors' noise
  // (about a degree for MEMS accelerometers and magnetometers at body-worn rates).
  static constexpr double kScatterTau_s = 2.0;
  static constexpr double kMinSampleSigma_rad = 3.14159265358979 / 180.0;

  // Inclination.
  Vec3 acc_lp1_I_ = Vec3::Zero();              // first low-pass stage
  Vec3 acc_lp_I_ = Vec3::Zero();               // second stage: the filtered vector
  Vec3 acc_correction_rate_E_ = Vec3::Zero();  // last tilt correction / dt, for the bias

  // Rest detection and bias.
  Vec3 gyr_lp_ = Vec3::Zero();
  double rest_s_ = 0.0;
  // The current steady stretch: sums of the raw gyro, and the bias filter's state at its start.
  Vec3 rest_gyr_sum_ = Vec3::Zero();
  double rest_gyr_sq_sum_ = 0.0;
  double rest_count_ = 0.0;
  Vec3 rest_prior_bias_ = Vec3::Zero();
  double rest_prior_var_ = 0.0;
  Vec3 bias_ = Vec3::Zero();
  double bias_var_ = 0.0;
  // E_from_A low-passed like the accelerometer (two stages), for the motion bias update.
  Eigen::Matrix3d E_from_A_lp1_acc_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d E_from_A_m_ = Eigen::Matrix3d::Identity();  // this sample's E_from_A as a matrix
  Eigen::Matrix3d E_from_A_lp_acc_ = Eigen::Matrix3d::Zero();

  // Heading and magnetic reference.
  bool mag_ref_valid_ = false;
  double mag_ref_norm_ = 0.0;
  double mag_ref_sin_dip_ = 0.0;  // sine of the dip angle, positive when the field points down
  double mag_init_count_ = 0.0;
  bool mag_disturbed_ = false;
  double mag_clean_s_ = 0.0;  // time the field has fitted the reference without a break
  double mag_recover_left_s_ = 0.0;
  // Candidate for a new field.
  double cand_norm_ = 0.0, cand_sin_dip_ = 0.0, cand_s_ = 0.0;
  bool cand_valid_ = false;
  // Hard iron: current offset and the forgetting least-squares fit of [b_E; h_A].
  Vec3 hard_iron_uT_ = Vec3::Zero();
  Vec3 hard_iron_prev_uT_ = Vec3::Zero();
  double prev_fit_s_ = 0.0;
  Eigen::Matrix3d hi_A_from_E_sum_ = Eigen::Matrix3d::Zero();
  Vec3 hi_m_E_sum_ = Vec3::Zero();
  Vec3 hi_m_A_sum_ = Vec3::Zero();
  double hi_weight_ = 0.0;
  double hi_sum_sq_ = 0.0;
  double hi_check_s_ = 0.0;
  double hi_duration_s_ = 0.0;
};

}  // namespace posefuse::imu
