#pragma once
// IMU signal synthesis: what a cheap 9-axis IMU reports for a known motion (paper 1, II-D/E).
//
// Ideal signals in the sensor frame A, from the motion in W (sensor_trajectory.hpp):
//   angular rate     omega_A
//   specific force   f_A = A_from_W * (a_W + g z_W)     (reads +g up at rest)
//   magnetic field   m_A = A_from_W * m_W,  m_W = (H, 0, -H tan(dip))  (W: x magnetic north, z up)
// Measured signals (the error model below, all frames A):
//   gyr = (M_g + diag(k_g) dT(t)) omega_A + b_g(t) + c_g dT(t) + n_g
//   acc = (M_a + diag(k_a) dT(t)) f_A + b_a + c_a dT(t) + n_a
//   mag = S (m_A + A_from_W d_W(t)) + h + h_jump(t) + n_m
// with M scale and misalignment matrices, b biases (the gyro's drifts as a random walk), c the
// biases' and k the scale factors' change per kelvin, dT the sensor's warming since the first
// sample (SensorWarmUp),
// S soft iron (symmetric), h hard iron, d_W transient external fields and h_jump hard-iron
// steps (a magnet attached to the strap) from MagDisturbance events, n white noise.
// The inverse of the magnetometer part is paper 1 eq. 3 with S = H diag(alpha, beta, gamma) H^T.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "imu/imu_sample.hpp"
#include "posefuse/v1/session.pb.h"
#include "sim/sensor_trajectory.hpp"

namespace posefuse::sim {

using Mat3 = Eigen::Matrix3d;

// The local earth field. Defaults: a mid-latitude site (about 48 uT total, 64 degrees dip).
struct EarthField {
  double horizontal_uT = 21.0;                                  // horizontal (north) component, uT, > 0
  double dip_rad = 64.0 * static_cast<double>(EIGEN_PI) / 180;  // inclination below the horizon, rad, in (-pi/2, pi/2)
  Vec3 m_W_uT() const;                                          // (H, 0, -H tan(dip))
};

// Statistical description of a cheap consumer IMU (MEMS parts of the WICED Sense class).
// White noise densities are per sqrt(Hz): a sample at rate f has standard deviation
// density * sqrt(f), so that integrating the gyro gives an angle random walk of
// density * sqrt(T) per axis over T seconds. Zero disables a term.
struct ImuErrorModel {
  double gyr_noise_density_rad_s_sqrt_hz = 2.5e-4;  // 0.014 deg/s/sqrt(Hz)
  double acc_noise_density_m_s2_sqrt_hz = 1.5e-3;   // 150 ug/sqrt(Hz)
  double mag_noise_uT = 0.3;                        // per sample, standard deviation
  double gyr_bias_sigma_rad_s = 0.01;               // turn-on bias per axis (0.57 deg/s)
  double gyr_bias_random_walk_rad_s_sqrt_s = 1e-4;  // bias drift: std grows as this * sqrt(t)
  double acc_bias_sigma_m_s2 = 0.05;                // per axis (about 5 mg)
  double gyr_scale_sigma = 0.01;                    // relative, per axis (1 %)
  double acc_scale_sigma = 0.005;                   // relative, per axis (0.5 %)
  double misalignment_sigma_rad = 0.005;            // off-diagonal of M_g and M_a (0.3 deg)
  double hard_iron_sigma_uT = 10.0;                 // per axis
  double soft_iron_diagonal_sigma = 0.05;           // S = I + E, E symmetric: diagonal
  double soft_iron_off_diagonal_sigma = 0.02;       // and off-diagonal entries
  // The biases' change per kelvin of the sensor's temperature, per axis (only a warming sensor,
  // SensorWarmUp, shows it). Gyro: 0.03 deg/s/K, the ITG-3200 class's figure; the MPU-6050 class
  // allows +-20 deg/s over -40..85 C, about 0.16 deg/s/K (InvenSense's product specifications as
  // quoted on its developer forum, "Am I interpreting 6150/9150 gyro bias specs correctly?").
  // Accelerometer: 0.8 mg/K, the ICM-20948's zero-g level change over temperature (datasheet
  // DS-000189 rev. 1.3, table 2).
  double gyr_bias_per_kelvin_sigma_rad_s = 0.03 * static_cast<double>(EIGEN_PI) / 180.0;
  double acc_bias_per_kelvin_sigma_m_s2 = 0.8e-3 * 9.80665;
  // The scale factors' relative change per kelvin, per axis. Gyro: 1.6e-4 (0.016 %/K), the
  // MPU-6050's sensitivity scale factor variation of +-2 % over -40..85 C; Android's
  // compatibility definition asks high-fidelity gyros for at most 0.02 %/K, and newer parts
  // (ICM-42688-P) specify 0.005 %/K. Accelerometer: 2.6e-4 (0.026 %/K), the MPU-9250 class's
  // sensitivity change vs. temperature (Android asks for at most 0.03 %/K).
  double gyr_scale_per_kelvin_sigma = 1.6e-4;
  double acc_scale_per_kelvin_sigma = 2.6e-4;

  // All terms zero: ideal signals.
  static ImuErrorModel none();
};

// One realisation of the static errors of one device (ground truth of its calibration).
struct ImuErrors {
  Vec3 gyr_bias_rad_s = Vec3::Zero();  // at t = first sample; drifts from there
  Mat3 gyr_scale_misalignment = Mat3::Identity();
  Vec3 acc_bias_m_s2 = Vec3::Zero();
  Mat3 acc_scale_misalignment = Mat3::Identity();
  Vec3 hard_iron_uT = Vec3::Zero();
  Mat3 soft_iron = Mat3::Identity();  // symmetric positive definite
  Vec3 gyr_bias_per_kelvin_rad_s = Vec3::Zero();
  Vec3 acc_bias_per_kelvin_m_s2 = Vec3::Zero();
  Vec3 gyr_scale_per_kelvin = Vec3::Zero();  // k_g: relative, per axis
  Vec3 acc_scale_per_kelvin = Vec3::Zero();  // k_a
};

// Draws the static errors: M = diag(1 + s) + N (N off-diagonal only), S = I + E symmetric.
ImuErrors draw_imu_errors(const ImuErrorModel& model, std::uint64_t seed);

// A magnetic disturbance.
struct MagDisturbance {
  enum class Kind {
    kTransient,     // an external object passing by: field_uT (in W) times
                    // exp(-0.5 ((t - t_s) / width_s)^2)
    kHardIronJump,  // a magnet attached to the sensor: field_uT (in A) added from t_s on
  };
  Kind kind = Kind::kTransient;
  double t_s = 0.0;      // centre (transient) or onset (jump), camera clock seconds
  double width_s = 0.5;  // transient only, > 0
  Vec3 field_uT = Vec3::Zero();
};

// A sensor warming up after it is switched on and strapped to the skin: its temperature rises by
// rise_K * (1 - exp(-t / time_constant_s)) over the t seconds since the first sample. Ours: a wrist's
// skin is about 32-34 C against a room's 20-25 C, so a strap-on part warms by up to ~10 K, over
// minutes for a small housing. Off (0) by default: a device worn for a while before the session
// is at its temperature, and a minute of a 5-minute warm-up moves the gyro bias by ~0.05 deg/s.
struct SensorWarmUp {
  double rise_K = 0.0;             // >= 0
  double time_constant_s = 300.0;  // > 0
  double rise_at(double seconds_since_first_sample) const;
};

// A datasheet's g, in which accelerometer ranges are given.
constexpr double kStandardGravity_m_s2 = 9.80665;

struct ImuSynthOptions {
  double nominal_rate_hz = 80.0;  // sets the white noise per sample (see ImuErrorModel)
  double gravity_m_s2 = 9.81;
  // Full scale: each axis of the measured gyro and accelerometer signal (errors included) is
  // clipped to +-range, as the ADC of a MEMS part saturates; defaults are common full scales
  // (2000 deg/s, 16 g) that a fast punch or a hand clap exceeds. > 0; infinity: no saturation.
  double gyr_range_rad_s = 2000.0 * static_cast<double>(EIGEN_PI) / 180.0;
  double acc_range_m_s2 = 16.0 * kStandardGravity_m_s2;
  EarthField earth_field;
  ImuErrorModel error_model;
  // The static errors; drawn from error_model with the seed when not given.
  std::optional<ImuErrors> errors;
  std::vector<MagDisturbance> disturbances;
  SensorWarmUp warm_up;
  std::uint64_t seed = 1;
};

struct ImuSynthResult {
  std::vector<imu::ImuSample> samples;  // t_us = round(t_s * 1e6): the camera clock
  ImuErrors errors;                     // what was applied
  std::vector<Vec3> gyr_bias_rad_s;     // true gyro bias at each sample (drift and warm-up included)
  std::vector<Quat> W_from_A;           // true orientation at each sample
};

// Samples at the given times (camera clock seconds, strictly increasing, inside the
// trajectory's valid range). Throws kInvalidArgument / kOutOfRange naming the field.
ImuSynthResult synthesize_imu(const SensorKinematics& motion, const std::vector<double>& t_s,
                              const ImuSynthOptions& options);

// t_begin + k / rate_hz for all k with the time <= t_end.
std::vector<double> uniform_times(double t_begin_s, double t_end_s, double rate_hz);

// The samples cut into ImuBatch chunks of at most `samples_per_batch` samples.
std::vector<v1::ImuBatch> imu_batches(const std::string& device_id, const std::vector<imu::ImuSample>& samples,
                                      std::size_t samples_per_batch = 32);

}  // namespace posefuse::sim
