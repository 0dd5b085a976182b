#pragma once
// Synthetic arm for forearm tests and bench/bench_forearm_gaps: a forearm swinging on a sphere
// around a shoulder. The IMU position is exactly
//   p(t) = S(t) + d_ul U(t) + K_from_F(t) [r, d_se, 0]      (elbow on the shoulder sphere, eq. 13)
// with U the upper-arm direction, and the arm IMU's specific force is exact:
//   f_A = A_from_K (p''(t) + g_K),  g_K = K_from_W [0, 0, 9.81],
// p'' by a 5-point central difference (truncation and rounding both < 1e-8 m/s^2 here).
// Noise, bias, orientation error and occlusion are added on top by make_gap_input.
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "forearm/forearm_model.hpp"
#include "forearm/gap_input.hpp"
#include "geometry/quaternion.hpp"

namespace posefuse::forearm::testing {

struct ArmMotion {
  Vec3 shoulder_K{0.2, 0.3, 2.0};  // 2 m in front of the camera (paper III)
  Vec3 shoulder_sway_m{0.01, 0.005, 0.01};
  double sway_hz = 0.2;
  double azimuth0 = 0.3, azimuth_amp = 0.9, azimuth_hz = 0.5, azimuth_phase = 0.0;
  double elevation0 = -0.6, elevation_amp = 0.5, elevation_hz = 0.5, elevation_phase = 1.0;
  Vec3 forearm_rv0{0.3, 0.2, 1.2};  // K_from_F rotation vector at rest (rad)
  Vec3 forearm_rv_amp{0.6, 0.8, 0.5};
  double forearm_hz = 0.5, forearm_phase = 0.4;
  ForearmModel model{0.03, 0.22, 0.04, 0.30, geometry::quat_from_rotation_vector(Vec3(0.1, -0.2, 0.3))};
  Quat K_from_W = Quat(Eigen::AngleAxisd(-std::numbers::pi / 2, Vec3::UnitX())) *
                  Quat(Eigen::AngleAxisd(0.4, Vec3::UnitZ()));  // W up -> K y (up)

  Vec3 shoulder(double t) const {
    const double s = std::sin(2.0 * std::numbers::pi * sway_hz * t);
    return shoulder_K + s * shoulder_sway_m;
  }
  Vec3 upper_arm_direction(double t) const {
    const double w = 2.0 * std::numbers::pi;
    const double az = azimuth0 + azimuth_amp * std::sin(w * azimuth_hz * t + azimuth_phase);
    const double el = elevation0 + elevation_amp * std::sin(w * elevation_hz * t + elevation_phase);
    return Vec3(std::cos(el) * std::sin(az), std::sin(el), -std::cos(el) * std::cos(az));
  }
  Quat K_from_F(double t) const {
    const double s = std::sin(2.0 * std::numbers::pi * forearm_hz * t + forearm_phase);
    return geometry::quat_from_rotation_vector(forearm_rv0 + s * forearm_rv_amp);
  }
  Quat K_from_A(double t) const { return K_from_F(t) * model.F_from_A; }
  Vec3 elbow(double t) const { return shoulder(t) + model.d_ul_m * upper_arm_direction(t); }
  Vec3 wrist(double t) const { return elbow(t) + K_from_F(t) * Vec3(0.0, model.d_se_m + model.d_sw_m, 0.0); }
  Vec3 imu_position(double t) const { return elbow(t) + K_from_F(t) * Vec3(model.r_m, model.d_se_m, 0.0); }
  Vec3 acceleration(double t) const {
    const double h = 1e-3;
    return (-imu_position(t + 2 * h) + 16.0 * imu_position(t + h) - 30.0 * imu_position(t) +
            16.0 * imu_position(t - h) - imu_position(t - 2 * h)) /
           (12.0 * h * h);
  }
  Vec3 specific_force_A(double t) const {
    return K_from_A(t).conjugate() * (acceleration(t) + K_from_W * Vec3(0.0, 0.0, kGravity));
  }
};

struct SensorNoise {
  double track_sigma_m = 0.005;  // depth-camera position noise
  double shoulder_sigma_m = 0.005;
  double acc_sigma_m_s2 = 0.05;  // white accelerometer noise
  Vec3 acc_bias_A{0.08, -0.06, 0.05};
  double attitude_drift_deg = 2.0;  // slowly wandering orientation-filter error (leaks gravity)
  double attitude_noise_deg = 0.3;  // white orientation jitter
  unsigned seed = 1;
};

inline double seconds(std::int64_t t_us) { return static_cast<double>(t_us) * 1e-6; }

inline SensorNoise noise_free() {
  return {.track_sigma_m = 0,
          .shoulder_sigma_m = 0,
          .acc_sigma_m_s2 = 0,
          .acc_bias_A = Vec3::Zero(),
          .attitude_drift_deg = 0,
          .attitude_noise_deg = 0};
}

// A session [0, duration_s] with the track occluded in (gap_start_s, gap_end_s).
// Camera 30 Hz, arm IMU 80 Hz with a 3 ms phase offset.
inline GapRecoveryInput make_gap_input(const ArmMotion& motion, const SensorNoise& noise, double duration_s,
                                       double gap_start_s, double gap_end_s) {
  std::mt19937 rng(noise.seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  auto gauss3 = [&](double sigma) -> Vec3 {
    const double x = n01(rng), y = n01(rng), z = n01(rng);
    return Vec3(x, y, z) * sigma;
  };
  GapRecoveryInput in;
  in.model = motion.model;
  in.K_from_W = motion.K_from_W;
  for (std::int64_t t = 0; seconds(t) <= duration_s; t += 33'333) {
    const double ts = seconds(t);
    TrackSample s{t, motion.imu_position(ts) + gauss3(noise.track_sigma_m), !(ts > gap_start_s && ts < gap_end_s)};
    if (!s.visible) s.p_K = Vec3::Constant(std::nan(""));
    in.track.push_back(s);
    in.shoulder.push_back({t, motion.shoulder(ts) + gauss3(noise.shoulder_sigma_m)});
  }
  for (std::int64_t t = 3'000; seconds(t) <= duration_s; t += 12'500) {
    const double ts = seconds(t);
    const double deg = std::numbers::pi / 180.0;
    const Vec3 drift(std::sin(2.0 * std::numbers::pi * 0.23 * ts), std::cos(2.0 * std::numbers::pi * 0.17 * ts),
                     std::sin(2.0 * std::numbers::pi * 0.31 * ts + 1.0));
    const Vec3 attitude_error =
        drift * (noise.attitude_drift_deg * deg / std::sqrt(3.0)) + gauss3(noise.attitude_noise_deg * deg);
    in.arm.push_back({t, geometry::quat_from_rotation_vector(attitude_error) * motion.K_from_A(ts),
                      motion.specific_force_A(ts) + noise.acc_bias_A + gauss3(noise.acc_sigma_m_s2)});
  }
  return in;
}

// The camera skeleton's elbow anchor (GapRecoveryInput::elbow_anchor) at every track frame: the
// true IMU position plus the SDK's elbow error as the simulator makes it (camera_skeleton.hpp):
// a bias of bias_m turning in a plane with period bias_period_s, jitter, and with probability
// jump_probability per frame a jump of jump_m.
struct AnchorError {
  double bias_m = 0.08;
  double bias_period_s = 10.0;
  double jitter_sigma_m = 0.004;
  double jump_probability = 0.03;
  double jump_m = 0.25;
  unsigned seed = 7;
};
inline void add_elbow_anchor(GapRecoveryInput& in, const ArmMotion& motion, const AnchorError& error) {
  std::mt19937 rng(error.seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const Vec3 u = Vec3(1.0, 0.3, -0.2).normalized(), v = u.cross(Vec3::UnitY()).normalized();
  for (const TrackSample& s : in.track) {
    const double t = seconds(s.t_us), w = 2.0 * std::numbers::pi / error.bias_period_s;
    Vec3 e = error.bias_m * (std::cos(w * t) * u + std::sin(w * t) * v) +
             error.jitter_sigma_m * Vec3(n01(rng), n01(rng), n01(rng));
    if (u01(rng) < error.jump_probability) e += error.jump_m * Vec3(n01(rng), n01(rng), n01(rng)).normalized();
    in.elbow_anchor.push_back({s.t_us, motion.imu_position(t) + e});
  }
}

// The one gap of a track (std::runtime_error when there is not exactly one).
inline GapSpan only_gap(const GapRecoveryInput& in) {
  const std::vector<GapSpan> gaps = find_gaps(in.track);
  if (gaps.size() != 1) throw std::runtime_error("expected one gap, found " + std::to_string(gaps.size()));
  return gaps.front();
}

struct GapErrors {
  double rms_m = 0.0;
  double max_m = 0.0;
};

// Errors of a recovered gap against the true IMU position at every recovered time.
inline GapErrors gap_errors(const ArmMotion& motion, const RecoveredGap& gap) {
  GapErrors e;
  double sum_sq = 0.0;
  for (std::size_t i = 0; i < gap.t_us.size(); ++i) {
    const double d = (gap.p_K[i] - motion.imu_position(seconds(gap.t_us[i]))).norm();
    sum_sq += d * d;
    e.max_m = std::max(e.max_m, d);
  }
  e.rms_m = std::sqrt(sum_sq / static_cast<double>(gap.t_us.size()));
  return e;
}

// `count` camera frames (30 Hz) of the pose of time t held still: exact joints, strap, SDK
// forearm orientation and arm IMU (a calibration hold, paper 1 II-H).
inline std::vector<CalibrationFrame> held_pose_frames(const ArmMotion& motion, double t = 0.3, int count = 40) {
  std::vector<CalibrationFrame> frames;
  for (int k = 0; k < count; ++k) {
    const Quat K_from_F = motion.K_from_F(t);
    CalibrationFrame f;
    f.t_us = k * 33'333;
    f.shoulder_K = motion.shoulder(t);
    f.elbow_K = motion.elbow(t);
    f.wrist_K = motion.wrist(t);
    f.strap_K = motion.imu_position(t);
    f.K_from_F_sdk = K_from_F;
    f.W_from_A = motion.K_from_W.conjugate() * K_from_F * motion.model.F_from_A;
    frames.push_back(f);
  }
  return frames;
}

}  // namespace posefuse::forearm::testing
