// The robust orientation filter against disturbances that BROAD's shared trials under-represent,
// simulated with the project's IMU error model (core/sim/imu_synth.hpp): error against strength.
//
//   bench_imu_disturbances [--mode robust|robust-offline] [--seeds FIRST-LAST] [--rate HZ]
//                          [--gyro-scale-sigma S] [--gyro-per-kelvin-sigma DEG_S_K] [--family NAME]
//
// Every case is a 150 s recording at the rate (default BROAD's 285.7 Hz): 5 s of rest, then
// varied rotation about all axes with a small translation, from one motion seed. The sensor is
// a cheap MEMS part (ImuErrorModel defaults: 1 % gyro scale, 0.57 deg/s turn-on bias with drift)
// whose magnetometer was calibrated beforehand up to a residual (1 uT hard iron, 1 % soft iron),
// as BROAD's vendor calibration is. Families, each a table row per strength:
//   attached magnet     a sensor-fixed offset (hard iron) of S uT from 40 s to 100 s
//   magnet duration     a 30 uT offset attached at 40 s for S seconds
//   stationary magnet   a field of S uT in W, passing by every 15 s (Gaussian, 1.5 s wide)
//   fast with breaks    peak rate S rad/s, 10 s rest breaks every 25 s
//   break length        peak rate 8 rad/s, breaks of S seconds every 25 s
//   vibration           40 Hz acceleration of S m/s^2 amplitude on the accelerometer
//   tapping             taps of S m/s^2 (10 ms half-sine) twice a second on the accelerometer
//   bias step           the gyro bias steps by S deg/s in the middle of a 10 s break at 70 s
//   sensor warm-up      the sensor warms by S kelvin from its first sample (time constant 60 s), its
//                       biases with it at the error model's spread per kelvin (sim::SensorWarmUp)
// Printed per row: mean over seeds of the total RMSE (deg, over the whole recording after the
// first 5 s, breaks included), its worst seed, and the largest single-sample error. The ground truth is the
// simulator's.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "eval/orientation_error.hpp"
#include "geometry/quaternion.hpp"
#include "imu/robust_offline.hpp"
#include "imu/robust_orientation_filter.hpp"
#include "sim/imu_synth.hpp"
#include "sim/sensor_trajectory.hpp"

namespace {

using posefuse::geometry::Quat;
using posefuse::geometry::Vec3;
using posefuse::imu::ImuSample;
namespace sim = posefuse::sim;

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
constexpr double kDurationS = 150.0;
constexpr double kStartRestS = 5.0;
constexpr double kGridDtS = 1e-3;

// One recording to simulate.
struct Case {
  double peak_rate_rad_s = 2.0;
  double break_every_s = 0.0;  // 0: no breaks
  double break_s = 0.0;
  std::vector<sim::MagDisturbance> disturbances;
  std::function<Vec3(double)> extra_acc_m_s2;  // added to the accelerometer (sensor frame)
  double bias_step_t_s = -1.0;                 // < 0: none
  Vec3 bias_step_rad_s = Vec3::Zero();
  sim::SensorWarmUp warm_up;
};

// 0 at rest, 1 in motion, raised-cosine ramps of 0.5 s so that rates and accelerations stay
// smooth. After the first rest, each period of break_every_s is motion, then break_s of rest.
double motion_envelope(const Case& c, double t) {
  const auto ramp = [](double x) { return x <= 0 ? 0.0 : x >= 1 ? 1.0 : 0.5 - 0.5 * std::cos(kPi * x); };
  const double u = t - kStartRestS;
  if (u <= 0.0) return 0.0;
  if (c.break_every_s <= 0.0) return ramp(u / 0.5);
  const double phase = std::fmod(u, c.break_every_s);
  const double moving_s = c.break_every_s - c.break_s;
  if (phase >= moving_s) return 0.0;
  return ramp(phase / 0.5) * ramp((moving_s - phase) / 0.5);
}

// Body rate: three incommensurate sines per axis with seeded phases, scaled to the peak rate.
struct MotionShape {
  double freq_hz[3][3];
  double phase[3][3];
};

MotionShape motion_shape(unsigned seed) {
  MotionShape m{};
  std::uint64_t x = 0x9E3779B97F4A7C15ULL * (seed + 1);
  const auto uniform = [&x] {
    x ^= x >> 12, x ^= x << 25, x ^= x >> 27;
    return static_cast<double>((x * 0x2545F4914F6CDD1DULL) >> 11) * 0x1.0p-53;
  };
  for (int a = 0; a < 3; ++a) {
    for (int k = 0; k < 3; ++k) {
      m.freq_hz[a][k] = 0.08 + 0.5 * uniform();
      m.phase[a][k] = 2.0 * kPi * uniform();
    }
  }
  return m;
}

sim::SensorTrajectory trajectory(const Case& c, const MotionShape& shape) {
  sim::SensorTrajectory traj;
  traj.t0_s = -0.01;
  traj.dt_s = kGridDtS;
  const auto n = static_cast<std::size_t>((kDurationS + 0.02) / kGridDtS) + 1;
  Quat q(Eigen::AngleAxisd(0.4, Vec3(1, -2, 0.5).normalized()));
  for (std::size_t i = 0; i < n; ++i) {
    const double t = traj.t0_s + static_cast<double>(i) * kGridDtS;
    const double e = motion_envelope(c, t);
    Vec3 w;
    for (int a = 0; a < 3; ++a) {
      double v = 0.0;
      for (int k = 0; k < 3; ++k) v += std::sin(2.0 * kPi * shape.freq_hz[a][k] * t + shape.phase[a][k]);
      w[a] = v / 3.0;
    }
    if (i > 0)
      q = (q * posefuse::geometry::quat_from_rotation_vector(e * c.peak_rate_rad_s * kGridDtS * w)).normalized();
    traj.W_from_A.push_back(q);
    traj.p_W_m.push_back(Vec3(0.15 * std::sin(0.9 * t), 0.1 * std::sin(1.3 * t + 1.0), 0.05 * std::sin(2.1 * t)) * e);
  }
  return traj;
}

struct Score {
  double rmse_deg = 0.0;
  double max_deg = 0.0;
};

Score run_case(const Case& c, unsigned seed, bool offline, double rate_hz, double gyro_scale_sigma,
               double gyro_per_kelvin_sigma_rad_s) {
  const MotionShape shape = motion_shape(seed);
  const sim::SensorKinematics kinematics(trajectory(c, shape));
  sim::ImuSynthOptions options;
  options.nominal_rate_hz = rate_hz;
  options.error_model.gyr_scale_sigma = gyro_scale_sigma;
  options.error_model.gyr_bias_per_kelvin_sigma_rad_s = gyro_per_kelvin_sigma_rad_s;
  options.error_model.hard_iron_sigma_uT = 1.0;  // calibrated beforehand, up to a residual
  options.error_model.soft_iron_diagonal_sigma = 0.01;
  options.error_model.soft_iron_off_diagonal_sigma = 0.005;
  options.disturbances = c.disturbances;
  options.warm_up = c.warm_up;
  options.seed = seed;
  const std::vector<double> t = sim::uniform_times(0.0, kDurationS, rate_hz);
  sim::ImuSynthResult imu = sim::synthesize_imu(kinematics, t, options);
  for (std::size_t i = 0; i < imu.samples.size(); ++i) {
    ImuSample& s = imu.samples[i];
    if (c.extra_acc_m_s2) s.acc_m_s2 += c.extra_acc_m_s2(t[i]);
    if (c.bias_step_t_s >= 0.0 && t[i] >= c.bias_step_t_s) s.gyr_rad_s += c.bias_step_rad_s;
  }
  std::vector<Quat> W_from_A;
  if (offline) {
    W_from_A = posefuse::imu::robust_orientation_offline(imu.samples);
  } else {
    posefuse::imu::RobustOrientationFilter filter;
    W_from_A = filter.process(imu.samples);
  }
  std::vector<bool> counted(t.size());
  Score score;
  for (std::size_t i = 0; i < t.size(); ++i) {
    counted[i] = t[i] > kStartRestS;
    if (counted[i]) {
      score.max_deg =
          std::max(score.max_deg, posefuse::eval::orientation_error(W_from_A[i], imu.W_from_A[i]).total_rad / kDeg);
    }
  }
  score.rmse_deg = posefuse::eval::orientation_rmse(W_from_A, imu.W_from_A, counted).total_rad / kDeg;
  return score;
}

// A unit direction from the seed, for sensor-fixed and external fields.
Vec3 seeded_direction(unsigned seed, unsigned salt) {
  const double a = 2.39996323 * (seed * 7 + salt), z = std::cos(1.3 * (seed * 3 + salt) + 0.4);
  const double r = std::sqrt(1.0 - z * z);
  return Vec3(r * std::cos(a), r * std::sin(a), z);
}

struct Family {
  const char* name;
  const char* unit;
  std::vector<double> strengths;
  std::function<Case(double strength, unsigned seed)> make;
};

std::vector<Family> families() {
  using Kind = sim::MagDisturbance::Kind;
  const auto attached = [](double field_uT, double on_s, double off_s, unsigned seed) {
    const Vec3 f = field_uT * seeded_direction(seed, 1);
    return std::vector<sim::MagDisturbance>{{Kind::kHardIronJump, on_s, 0.5, f}, {Kind::kHardIronJump, off_s, 0.5, -f}};
  };
  return {
      {"attached magnet",
       "uT",
       {0, 3, 6, 10, 20, 50, 150},
       [=](double s, unsigned seed) {
         Case c;
         c.disturbances = attached(s, 40, 100, seed);
         return c;
       }},
      {"magnet duration",
       "s",
       {5, 15, 30, 60, 100},
       [=](double s, unsigned seed) {
         Case c;
         c.disturbances = attached(30, 40, 40 + s, seed);
         return c;
       }},
      {"stationary magnet",
       "uT",
       {5, 10, 20, 40, 80},
       [=](double s, unsigned seed) {
         Case c;
         for (double t = 20; t < kDurationS - 5; t += 15) {
           c.disturbances.push_back({Kind::kTransient, t, 1.5, s * seeded_direction(seed, static_cast<unsigned>(t))});
         }
         return c;
       }},
      {"fast with breaks",
       "rad/s",
       {2, 5, 10, 15, 20},
       [](double s, unsigned) {
         Case c;
         c.peak_rate_rad_s = s;
         c.break_every_s = 25;
         c.break_s = 10;
         return c;
       }},
      {"break length",
       "s",
       {2, 5, 10, 20},
       [](double s, unsigned) {
         Case c;
         c.peak_rate_rad_s = 8;
         c.break_every_s = 25;
         c.break_s = s;
         return c;
       }},
      {"vibration",
       "m/s^2",
       {1, 3, 10, 30},
       [](double s, unsigned seed) {
         Case c;
         const Vec3 d = seeded_direction(seed, 2);
         c.extra_acc_m_s2 = [=](double t) { return Vec3(s * std::sin(2 * kPi * 40 * t) * d); };
         return c;
       }},
      {"tapping",
       "m/s^2",
       {10, 30, 100},
       [](double s, unsigned seed) {
         Case c;
         const Vec3 d = seeded_direction(seed, 3);
         c.extra_acc_m_s2 = [=](double t) {
           const double u = std::fmod(t, 0.5);
           return Vec3((u < 0.01 ? s * std::sin(kPi * u / 0.01) : 0.0) * d);
         };
         return c;
       }},
      {"bias step",
       "deg/s",
       {0.5, 1, 2, 4},
       [](double s, unsigned seed) {
         Case c;
         c.break_every_s = 65;  // one break, 60-70 s
         c.break_s = 10;
         c.bias_step_t_s = 65;
         c.bias_step_rad_s = s * kDeg * seeded_direction(seed, 4);
         return c;
       }},
      {"sensor warm-up",
       "K",
       {0, 5, 10, 20},
       [](double s, unsigned) {
         Case c;
         c.warm_up.rise_K = s;
         c.warm_up.time_constant_s = 60;
         return c;
       }},
  };
}

int run(int argc, char** argv) {
  bool offline = false;
  unsigned first_seed = 1, last_seed = 4;
  double rate_hz = 2000.0 / 7.0;
  double gyro_scale_sigma = sim::ImuErrorModel().gyr_scale_sigma;
  double gyro_per_kelvin_sigma_rad_s = sim::ImuErrorModel().gyr_bias_per_kelvin_sigma_rad_s;
  std::string only_family;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--mode" && i + 1 < argc) {
      const std::string m = argv[++i];
      if (m != "robust" && m != "robust-offline")
        throw posefuse::Error(posefuse::ErrorCode::kInvalidArgument, "--mode", "must be robust or robust-offline");
      offline = m == "robust-offline";
    } else if (arg == "--seeds" && i + 1 < argc) {
      if (std::sscanf(argv[++i], "%u-%u", &first_seed, &last_seed) != 2 || first_seed > last_seed) {
        throw posefuse::Error(posefuse::ErrorCode::kInvalidArgument, "--seeds", "must be FIRST-LAST, e.g. 1-4");
      }
    } else if (arg == "--rate" && i + 1 < argc) {
      rate_hz = std::atof(argv[++i]);
      if (!(rate_hz >= 20.0 && rate_hz <= 2000.0))
        throw posefuse::Error(posefuse::ErrorCode::kInvalidArgument, "--rate", "must be 20..2000 Hz");
    } else if (arg == "--gyro-scale-sigma" && i + 1 < argc) {
      gyro_scale_sigma = std::atof(argv[++i]);
      if (!(gyro_scale_sigma >= 0.0 && gyro_scale_sigma <= 0.1))
        throw posefuse::Error(posefuse::ErrorCode::kInvalidArgument, "--gyro-scale-sigma", "must be 0..0.1");
    } else if (arg == "--gyro-per-kelvin-sigma" && i + 1 < argc) {
      const double deg_s_k = std::atof(argv[++i]);
      if (!(deg_s_k >= 0.0 && deg_s_k <= 1.0))
        throw posefuse::Error(posefuse::ErrorCode::kInvalidArgument, "--gyro-per-kelvin-sigma", "must be 0..1 deg/s/K");
      gyro_per_kelvin_sigma_rad_s = deg_s_k * kDeg;
    } else if (arg == "--family" && i + 1 < argc) {
      only_family = argv[++i];
    } else {
      std::fprintf(stderr,
                   "usage: bench_imu_disturbances [--mode robust|robust-offline] [--seeds FIRST-LAST] [--rate HZ] "
                   "[--gyro-scale-sigma S] [--gyro-per-kelvin-sigma DEG_S_K] [--family NAME]\n");
      return 2;
    }
  }
  std::printf("robust filter %s, seeds %u-%u, %.1f Hz, %.0f s per case, gyro scale error sigma %.3g\n",
              offline ? "offline" : "causal", first_seed, last_seed, rate_hz, kDurationS, gyro_scale_sigma);
  if (gyro_per_kelvin_sigma_rad_s != sim::ImuErrorModel().gyr_bias_per_kelvin_sigma_rad_s)
    std::printf("gyro bias change per kelvin sigma %.3g deg/s/K\n", gyro_per_kelvin_sigma_rad_s / kDeg);
  std::vector<Family> chosen;
  std::string names;
  for (Family& family : families()) {
    names += std::string(names.empty() ? "" : ", ") + family.name;
    if (only_family.empty() || only_family == family.name) chosen.push_back(std::move(family));
  }
  if (chosen.empty())
    throw posefuse::Error(posefuse::ErrorCode::kInvalidArgument, "--family", "must be one of " + names);
  std::printf("%-18s %10s %10s %10s %10s\n", "family", "strength", "RMSE mean", "RMSE worst", "max error");
  for (const Family& family : chosen) {
    for (double strength : family.strengths) {
      double sum = 0.0, worst = 0.0, max_err = 0.0;
      for (unsigned seed = first_seed; seed <= last_seed; ++seed) {
        const Score s = run_case(family.make(strength, seed), seed, offline, rate_hz, gyro_scale_sigma,
                                 gyro_per_kelvin_sigma_rad_s);
        sum += s.rmse_deg;
        worst = std::max(worst, s.rmse_deg);
        max_err = std::max(max_err, s.max_deg);
      }
      char label[32];
      std::snprintf(label, sizeof label, "%g %s", strength, family.unit);
      std::printf("%-18s %10s %10.2f %10.2f %10.2f\n", family.name, label,
                  sum / static_cast<double>(last_seed - first_seed + 1), worst, max_err);
      std::fflush(stdout);
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const posefuse::Error& e) {
    std::fprintf(stderr, "bench_imu_disturbances: %s (%s)\n", e.what(), posefuse::error_code_name(e.code()));
    return 1;
  }
}
