#include "sim/imu_synth.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "common/error.hpp"
#include "session/imu_batch.hpp"
#include "sim/option_checks.hpp"
#include "sim/sim_rng.hpp"

namespace posefuse::sim {
namespace {

Vec3 normal_vec(SimRng& rng, double sigma) {
  const double x = rng.normal();
  const double y = rng.normal();
  const double z = rng.normal();
  return sigma * Vec3(x, y, z);
}

Mat3 scale_misalignment(SimRng& rng, double scale_sigma, double misalignment_sigma) {
  Mat3 m = Mat3::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      const double draw = rng.normal();
      m(r, c) += (r == c ? scale_sigma : misalignment_sigma) * draw;
    }
  }
  return m;
}

Vec3 saturated(const Vec3& v, double range) { return v.cwiseMax(-range).cwiseMin(range); }

void check_model(const ImuErrorModel& m) {
  require_non_negative(m.gyr_noise_density_rad_s_sqrt_hz, "error_model.gyr_noise_density_rad_s_sqrt_hz");
  require_non_negative(m.acc_noise_density_m_s2_sqrt_hz, "error_model.acc_noise_density_m_s2_sqrt_hz");
  require_non_negative(m.mag_noise_uT, "error_model.mag_noise_uT");
  require_non_negative(m.gyr_bias_sigma_rad_s, "error_model.gyr_bias_sigma_rad_s");
  require_non_negative(m.gyr_bias_random_walk_rad_s_sqrt_s, "error_model.gyr_bias_random_walk_rad_s_sqrt_s");
  require_non_negative(m.acc_bias_sigma_m_s2, "error_model.acc_bias_sigma_m_s2");
  require_non_negative(m.gyr_scale_sigma, "error_model.gyr_scale_sigma");
  require_non_negative(m.acc_scale_sigma, "error_model.acc_scale_sigma");
  require_non_negative(m.misalignment_sigma_rad, "error_model.misalignment_sigma_rad");
  require_non_negative(m.hard_iron_sigma_uT, "error_model.hard_iron_sigma_uT");
  require_non_negative(m.soft_iron_diagonal_sigma, "error_model.soft_iron_diagonal_sigma");
  require_non_negative(m.soft_iron_off_diagonal_sigma, "error_model.soft_iron_off_diagonal_sigma");
  require_non_negative(m.gyr_bias_per_kelvin_sigma_rad_s, "error_model.gyr_bias_per_kelvin_sigma_rad_s");
  require_non_negative(m.acc_bias_per_kelvin_sigma_m_s2, "error_model.acc_bias_per_kelvin_sigma_m_s2");
  require_non_negative(m.gyr_scale_per_kelvin_sigma, "error_model.gyr_scale_per_kelvin_sigma");
  require_non_negative(m.acc_scale_per_kelvin_sigma, "error_model.acc_scale_per_kelvin_sigma");
}

void check_errors(const ImuErrors& e) {
  if (!e.gyr_bias_rad_s.allFinite() || !e.gyr_scale_misalignment.allFinite() || !e.acc_bias_m_s2.allFinite() ||
      !e.acc_scale_misalignment.allFinite() || !e.hard_iron_uT.allFinite() || !e.soft_iron.allFinite() ||
      !e.gyr_bias_per_kelvin_rad_s.allFinite() || !e.acc_bias_per_kelvin_m_s2.allFinite() ||
      !e.gyr_scale_per_kelvin.allFinite() || !e.acc_scale_per_kelvin.allFinite()) {
    throw_invalid("errors", "non-finite value in the IMU errors");
  }
  if (!e.soft_iron.isApprox(e.soft_iron.transpose(), 1e-12)) {
    throw_invalid("errors.soft_iron", "must be symmetric");
  }
  if (Eigen::SelfAdjointEigenSolver<Mat3>(e.soft_iron).eigenvalues().minCoeff() <= 0) {
    throw_invalid("errors.soft_iron", "must be positive definite");
  }
}

Vec3 disturbance_field(const std::vector<MagDisturbance>& events, double t_s, const Quat& A_from_W,
                       Vec3& hard_iron_jump_A) {
  Vec3 field_A = Vec3::Zero();
  hard_iron_jump_A.setZero();
  for (const MagDisturbance& d : events) {
    if (d.kind == MagDisturbance::Kind::kTransient) {
      const double x = (t_s - d.t_s) / d.width_s;
      field_A += std::exp(-0.5 * x * x) * (A_from_W * d.field_uT);
    } else if (t_s >= d.t_s) {
      hard_iron_jump_A += d.field_uT;
    }
  }
  return field_A;
}

}  // namespace

Vec3 EarthField::m_W_uT() const { return {horizontal_uT, 0.0, -horizontal_uT * std::tan(dip_rad)}; }

double SensorWarmUp::rise_at(double seconds_since_first_sample) const {
  return rise_K * -std::expm1(-std::max(0.0, seconds_since_first_sample) / time_constant_s);
}

ImuErrorModel ImuErrorModel::none() {
  ImuErrorModel m;
  m.gyr_noise_density_rad_s_sqrt_hz = 0;
  m.acc_noise_density_m_s2_sqrt_hz = 0;
  m.mag_noise_uT = 0;
  m.gyr_bias_sigma_rad_s = 0;
  m.gyr_bias_random_walk_rad_s_sqrt_s = 0;
  m.acc_bias_sigma_m_s2 = 0;
  m.gyr_scale_sigma = 0;
  m.acc_scale_sigma = 0;
  m.misalignment_sigma_rad = 0;
  m.hard_iron_sigma_uT = 0;
  m.soft_iron_diagonal_sigma = 0;
  m.soft_iron_off_diagonal_sigma = 0;
  m.gyr_bias_per_kelvin_sigma_rad_s = 0;
  m.acc_bias_per_kelvin_sigma_m_s2 = 0;
  m.gyr_scale_per_kelvin_sigma = 0;
  m.acc_scale_per_kelvin_sigma = 0;
  return m;
}

ImuErrors draw_imu_errors(const ImuErrorModel& model, std::uint64_t seed) {
  check_model(model);
  SimRng rng(seed, "imu_errors");
  ImuErrors e;
  e.gyr_bias_rad_s = normal_vec(rng, model.gyr_bias_sigma_rad_s);
  e.gyr_scale_misalignment = scale_misalignment(rng, model.gyr_scale_sigma, model.misalignment_sigma_rad);
  e.acc_bias_m_s2 = normal_vec(rng, model.acc_bias_sigma_m_s2);
  e.acc_scale_misalignment = scale_misalignment(rng, model.acc_scale_sigma, model.misalignment_sigma_rad);
  e.hard_iron_uT = normal_vec(rng, model.hard_iron_sigma_uT);
  Mat3 soft = Mat3::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = r; c < 3; ++c) {
      const double draw = rng.normal();
      const double v = (r == c ? model.soft_iron_diagonal_sigma : model.soft_iron_off_diagonal_sigma) * draw;
      soft(r, c) += v;
      if (r != c) soft(c, r) += v;
    }
  }
  e.soft_iron = soft;
  // Their own stream, so that the errors above are those of the same seed without them.
  SimRng temperature(seed, "imu_temperature");
  e.gyr_bias_per_kelvin_rad_s = normal_vec(temperature, model.gyr_bias_per_kelvin_sigma_rad_s);
  e.acc_bias_per_kelvin_m_s2 = normal_vec(temperature, model.acc_bias_per_kelvin_sigma_m_s2);
  e.gyr_scale_per_kelvin = normal_vec(temperature, model.gyr_scale_per_kelvin_sigma);
  e.acc_scale_per_kelvin = normal_vec(temperature, model.acc_scale_per_kelvin_sigma);
  // A draw far in the tail could make S singular; the defaults make that astronomically rare,
  // but large user sigmas must not produce a meaningless magnetometer silently.
  check_errors(e);
  return e;
}

std::vector<double> uniform_times(double t_begin_s, double t_end_s, double rate_hz) {
  require_positive(rate_hz, "rate_hz");
  require_interval(t_begin_s, t_end_s, "t_end_s");
  std::vector<double> t;
  const auto count = static_cast<std::size_t>(std::floor((t_end_s - t_begin_s) * rate_hz + 1e-9)) + 1;
  t.reserve(count);
  for (std::size_t k = 0; k < count; ++k) t.push_back(t_begin_s + static_cast<double>(k) / rate_hz);
  return t;
}

ImuSynthResult synthesize_imu(const SensorKinematics& motion, const std::vector<double>& t_s,
                              const ImuSynthOptions& options) {
  require_positive(options.nominal_rate_hz, "options.nominal_rate_hz");
  require_finite(options.gravity_m_s2, "options.gravity_m_s2");
  require_positive(options.earth_field.horizontal_uT, "options.earth_field.horizontal_uT");
  if (!(std::abs(options.earth_field.dip_rad) < static_cast<double>(EIGEN_PI) / 2)) {
    throw_invalid("options.earth_field.dip_rad", "must be inside (-pi/2, pi/2)");
  }
  check_model(options.error_model);
  if (!(options.gyr_range_rad_s > 0))
    throw_invalid("options.gyr_range_rad_s", "is " + std::to_string(options.gyr_range_rad_s) + ", must be > 0");
  if (!(options.acc_range_m_s2 > 0))
    throw_invalid("options.acc_range_m_s2", "is " + std::to_string(options.acc_range_m_s2) + ", must be > 0");
  require_non_negative(options.warm_up.rise_K, "options.warm_up.rise_K");
  require_positive(options.warm_up.time_constant_s, "options.warm_up.time_constant_s");
  for (std::size_t i = 0; i < options.disturbances.size(); ++i) {
    const MagDisturbance& d = options.disturbances[i];
    const std::string field = "options.disturbances[" + std::to_string(i) + "]";
    if (!std::isfinite(d.t_s) || !d.field_uT.allFinite()) throw_invalid(field, "non-finite value");
    if (d.kind == MagDisturbance::Kind::kTransient) require_positive(d.width_s, field + ".width_s");
  }
  for (std::size_t k = 0; k < t_s.size(); ++k) {
    if (!std::isfinite(t_s[k]) || (k > 0 && !(t_s[k] > t_s[k - 1]))) {
      throw_invalid("t_s[" + std::to_string(k) + "]", "sample times must be finite and strictly increasing");
    }
  }

  ImuSynthResult out;
  out.errors = options.errors ? *options.errors : draw_imu_errors(options.error_model, options.seed);
  check_errors(out.errors);
  const ImuErrors& e = out.errors;
  const ImuErrorModel& model = options.error_model;
  const double sqrt_rate = std::sqrt(options.nominal_rate_hz);
  const double gyr_sigma = model.gyr_noise_density_rad_s_sqrt_hz * sqrt_rate;
  const double acc_sigma = model.acc_noise_density_m_s2_sqrt_hz * sqrt_rate;
  const Vec3 m_W = options.earth_field.m_W_uT();
  const Vec3 gravity_up_W(0.0, 0.0, options.gravity_m_s2);

  SimRng noise(options.seed, "imu_noise");
  SimRng drift(options.seed, "imu_bias_drift");
  Vec3 gyr_bias = e.gyr_bias_rad_s;
  out.samples.reserve(t_s.size());
  out.gyr_bias_rad_s.reserve(t_s.size());
  out.W_from_A.reserve(t_s.size());
  for (std::size_t k = 0; k < t_s.size(); ++k) {
    const SensorMotion m = motion.at(t_s[k]);
    const Quat A_from_W = m.W_from_A.conjugate();
    if (k > 0) {
      gyr_bias += normal_vec(drift, model.gyr_bias_random_walk_rad_s_sqrt_s * std::sqrt(t_s[k] - t_s[k - 1]));
    }
    Vec3 hard_iron_jump_A;
    const Vec3 disturbance_A = disturbance_field(options.disturbances, t_s[k], A_from_W, hard_iron_jump_A);
    const double warming_K = options.warm_up.rise_at(t_s[k] - t_s.front());
    const Vec3 gyr_bias_now = gyr_bias + warming_K * e.gyr_bias_per_kelvin_rad_s;

    imu::ImuSample s;
    s.t_us = std::llround(t_s[k] * 1e6);
    const Vec3 omega_A = m.omega_A_rad_s;
    s.gyr_rad_s =
        saturated(e.gyr_scale_misalignment * omega_A + warming_K * e.gyr_scale_per_kelvin.cwiseProduct(omega_A) +
                      gyr_bias_now + normal_vec(noise, gyr_sigma),
                  options.gyr_range_rad_s);
    const Vec3 f_A = A_from_W * (m.a_W_m_s2 + gravity_up_W);
    s.acc_m_s2 = saturated(e.acc_scale_misalignment * f_A + warming_K * e.acc_scale_per_kelvin.cwiseProduct(f_A) +
                               e.acc_bias_m_s2 + warming_K * e.acc_bias_per_kelvin_m_s2 + normal_vec(noise, acc_sigma),
                           options.acc_range_m_s2);
    const Vec3 m_A = A_from_W * m_W + disturbance_A;
    s.mag_uT = e.soft_iron * m_A + e.hard_iron_uT + hard_iron_jump_A + normal_vec(noise, model.mag_noise_uT);
    out.samples.push_back(s);
    out.gyr_bias_rad_s.push_back(gyr_bias_now);
    out.W_from_A.push_back(m.W_from_A);
  }
  return out;
}

std::vector<v1::ImuBatch> imu_batches(const std::string& device_id, const std::vector<imu::ImuSample>& samples,
                                      std::size_t samples_per_batch) {
  if (samples_per_batch == 0) throw_invalid("samples_per_batch", "must be >= 1");
  std::vector<v1::ImuBatch> batches;
  for (std::size_t begin = 0; begin < samples.size(); begin += samples_per_batch) {
    const std::size_t end = std::min(samples.size(), begin + samples_per_batch);
    const std::vector<imu::ImuSample> part(samples.begin() + static_cast<std::ptrdiff_t>(begin),
                                           samples.begin() + static_cast<std::ptrdiff_t>(end));
    batches.push_back(session::batch_from_samples(device_id, part));
  }
  return batches;
}

}  // namespace posefuse::sim
