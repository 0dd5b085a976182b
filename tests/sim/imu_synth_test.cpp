#include "sim/imu_synth.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "common/error.hpp"
#include "session/imu_batch.hpp"
#include "test_motion.hpp"

using posefuse::Error;
using posefuse::geometry::angle_between;
using namespace posefuse::sim;
using namespace posefuse::sim::testing;

namespace {

constexpr double kDeg = pi / 180.0;

ImuSynthOptions ideal_options() {
  ImuSynthOptions o;
  o.error_model = ImuErrorModel::none();
  return o;
}

SensorKinematics complex_motion(double t1 = 10.2) {
  return SensorKinematics(sample_trajectory(complex_position, complex_orientation, 0.0, t1));
}

}  // namespace

TEST(ImuSynth, NoiseFreeGyroIntegratesToTruth) {
  const SensorKinematics motion = complex_motion();
  const std::vector<double> t = uniform_times(0.05, 10.05, 80.0);
  const ImuSynthResult r = synthesize_imu(motion, t, ideal_options());
  ASSERT_EQ(r.samples.size(), 801u);
  const Quat end = integrate_gyro(r.samples, complex_orientation(t.front()));
  const double error_deg = angle_between(end, complex_orientation(t.back())) / kDeg;
  EXPECT_LT(error_deg, 0.1);
  std::printf("noise-free gyro integrated over 10 s: %.3g deg from the truth\n", error_deg);
  // The motion is not trivial: it turns through many radians.
  double turned = 0;
  for (const auto& s : r.samples) turned += s.gyr_rad_s.norm() / 80.0;
  EXPECT_GT(turned, 30.0);
}

// With white gyro noise of density N only, the integrated angle error per axis has standard
// deviation N sqrt(T); the error vector's norm then has rms sqrt(3) N sqrt(T).
TEST(ImuSynth, NoisyGyroIntegratesWithinAngleRandomWalk) {
  const SensorKinematics motion = complex_motion();
  const std::vector<double> t = uniform_times(0.05, 10.05, 80.0);
  ImuSynthOptions o = ideal_options();
  o.error_model.gyr_noise_density_rad_s_sqrt_hz = ImuErrorModel().gyr_noise_density_rad_s_sqrt_hz;
  const double sigma = o.error_model.gyr_noise_density_rad_s_sqrt_hz * std::sqrt(10.0);
  double sum_sq = 0;
  constexpr int kRuns = 20;
  for (int seed = 1; seed <= kRuns; ++seed) {
    o.seed = static_cast<std::uint64_t>(seed);
    const ImuSynthResult r = synthesize_imu(motion, t, o);
    const double error =
        angle_between(integrate_gyro(r.samples, complex_orientation(t.front())), complex_orientation(t.back()));
    EXPECT_LT(error, 5.0 * sigma) << "seed " << seed;  // P(chi_3 > 5) ~ 1.5e-5
    sum_sq += error * error;
  }
  const double rms_ratio = std::sqrt(sum_sq / kRuns) / (std::sqrt(3.0) * sigma);
  std::printf("noisy gyro: rms end error / (sqrt(3) N sqrt(T)) = %.3f over %d seeds\n", rms_ratio, kRuns);
  EXPECT_GT(rms_ratio, 0.6);
  EXPECT_LT(rms_ratio, 1.4);
}

TEST(ImuSynth, SpecificForceAtRestReadsGravityUp) {
  const Quat tilted = rot(0.7, Vec3(1, 2, 3).normalized());
  const SensorKinematics still(
      sample_trajectory([](double) { return Vec3(1, 2, 3); }, [&](double) { return tilted; }, 0, 1));
  const ImuSynthResult r = synthesize_imu(still, uniform_times(0.1, 0.9, 80), ideal_options());
  for (const auto& s : r.samples) {
    EXPECT_LT((s.acc_m_s2 - tilted.conjugate() * Vec3(0, 0, 9.81)).norm(), 1e-9);
    EXPECT_LT(s.gyr_rad_s.norm(), 1e-9);
  }
  // Level sensor: exactly +g on z.
  const SensorKinematics level(
      sample_trajectory([](double) { return Vec3::Zero(); }, [](double) { return Quat::Identity(); }, 0, 1));
  const auto s = synthesize_imu(level, {0.5}, ideal_options()).samples.front();
  EXPECT_NEAR(s.acc_m_s2.z(), 9.81, 1e-9);
  EXPECT_NEAR(s.acc_m_s2.head<2>().norm(), 0.0, 1e-9);
}

TEST(ImuSynth, SpecificForceOnCircleIncludesCentripetalAcceleration) {
  // Sensor on a 0.5 m circle at 2 rad/s, facing along the radius (A's x outwards).
  const double w = 2.0, radius = 0.5;
  const SensorKinematics motion(
      sample_trajectory([&](double t) { return Vec3(radius * std::cos(w * t), radius * std::sin(w * t), 0); },
                        [&](double t) { return rot(w * t, Vec3::UnitZ()); }, 0, 3));
  const ImuSynthResult r = synthesize_imu(motion, uniform_times(0.1, 2.9, 80), ideal_options());
  for (const auto& s : r.samples) {
    EXPECT_LT((s.acc_m_s2 - Vec3(-w * w * radius, 0, 9.81)).norm(), 2e-5);
    EXPECT_LT((s.gyr_rad_s - Vec3(0, 0, w)).norm(), 1e-6);
  }
}

TEST(ImuSynth, MagnetometerDipAndNorm) {
  ImuSynthOptions o = ideal_options();
  o.earth_field.horizontal_uT = 30.0;
  o.earth_field.dip_rad = -20.0 * kDeg;  // southern hemisphere: the field points up
  const SensorKinematics motion = complex_motion(3.0);
  const ImuSynthResult r = synthesize_imu(motion, uniform_times(0.1, 2.9, 80), o);
  const double norm = 30.0 / std::cos(20.0 * kDeg);
  for (std::size_t k = 0; k < r.samples.size(); ++k) {
    const auto& s = r.samples[k];
    EXPECT_NEAR(s.mag_uT.norm(), norm, 1e-9);
    // In W: north component 30 uT, dip measured below the horizon.
    const Vec3 m_W = r.W_from_A[k] * s.mag_uT;
    EXPECT_NEAR(m_W.x(), 30.0, 1e-9);
    EXPECT_NEAR(m_W.y(), 0.0, 1e-9);
    EXPECT_NEAR(std::atan2(-m_W.z(), m_W.x()), -20.0 * kDeg, 1e-12);
  }
}

// Hard and soft iron: raw readings over many orientations lie on the ellipsoid
// (m - h)^T (S S^T)^-1 (m - h) = |m_W|^2. A general quadric fitted to them by least squares
// recovers the centre h and the shape (S S^T)^-1 / |m_W|^2 (paper 1, eq. 3 inverts this).
TEST(ImuSynth, HardAndSoftIronFormTheConfiguredEllipsoid) {
  ImuSynthOptions o = ideal_options();
  ImuErrors e;
  e.hard_iron_uT = Vec3(12.0, -7.0, 25.0);
  e.soft_iron << 1.10, 0.05, -0.02,  //
      0.05, 0.92, 0.03,              //
      -0.02, 0.03, 1.04;
  o.errors = e;
  // A tumbling sensor covering many orientations.
  const SensorKinematics motion(sample_trajectory(
      [](double) { return Vec3::Zero(); },
      [](double t) {
        return rot(2.1 * t, Vec3::UnitZ()) * rot(1.3 * std::sin(0.9 * t), Vec3::UnitY()) * rot(1.7 * t, Vec3::UnitX());
      },
      0, 20));
  const ImuSynthResult r = synthesize_imu(motion, uniform_times(0.1, 19.9, 50), o);
  const double b2 = o.earth_field.m_W_uT().squaredNorm();

  // x^T Q x + 2 u^T x = 1: 9 unknowns (Q symmetric).
  Eigen::MatrixXd a(static_cast<Eigen::Index>(r.samples.size()), 9);
  for (std::size_t k = 0; k < r.samples.size(); ++k) {
    const Vec3& m = r.samples[k].mag_uT;
    a.row(static_cast<Eigen::Index>(k)) << m.x() * m.x(), m.y() * m.y(), m.z() * m.z(), 2 * m.x() * m.y(),
        2 * m.x() * m.z(), 2 * m.y() * m.z(), 2 * m.x(), 2 * m.y(), 2 * m.z();
  }
  const Eigen::VectorXd x = a.colPivHouseholderQr().solve(Eigen::VectorXd::Ones(a.rows()));
  Mat3 q;
  q << x[0], x[3], x[4], x[3], x[1], x[5], x[4], x[5], x[2];
  const Vec3 u(x[6], x[7], x[8]);
  const Vec3 centre = -q.inverse() * u;
  const Mat3 shape = q / (1.0 + centre.dot(q * centre));
  EXPECT_LT((centre - e.hard_iron_uT).norm(), 1e-6);
  const Mat3 expected = (e.soft_iron * e.soft_iron.transpose()).inverse() / b2;
  EXPECT_LT((shape - expected).norm() / expected.norm(), 1e-8);
  // Undoing the distortion gives the earth field's norm back.
  for (const auto& s : r.samples) {
    EXPECT_NEAR((e.soft_iron.inverse() * (s.mag_uT - e.hard_iron_uT)).norm(), std::sqrt(b2), 1e-9);
  }
}

TEST(ImuSynth, MagneticDisturbances) {
  ImuSynthOptions o = ideal_options();
  const Vec3 transient_W(40, -10, 5);
  const Vec3 magnet_A(0, 60, 0);
  o.disturbances.push_back({MagDisturbance::Kind::kTransient, 1.0, 0.1, transient_W});
  o.disturbances.push_back({MagDisturbance::Kind::kHardIronJump, 2.0, 0.0, magnet_A});
  const Quat pose = rot(0.4, Vec3::UnitY());
  const SensorKinematics still(
      sample_trajectory([](double) { return Vec3::Zero(); }, [&](double) { return pose; }, 0, 3));
  const ImuSynthResult r = synthesize_imu(still, {0.2, 1.0, 1.1, 1.9, 2.0, 2.9}, o);
  const Vec3 clean = pose.conjugate() * o.earth_field.m_W_uT();
  EXPECT_LT((r.samples[0].mag_uT - clean).norm(), 1e-9);                                   // before
  EXPECT_LT((r.samples[1].mag_uT - clean - pose.conjugate() * transient_W).norm(), 1e-9);  // peak
  EXPECT_LT((r.samples[2].mag_uT - clean - std::exp(-0.5) * (pose.conjugate() * transient_W)).norm(), 1e-9);
  EXPECT_LT((r.samples[3].mag_uT - clean).norm(), 1e-9);             // 9 widths later: gone
  EXPECT_LT((r.samples[4].mag_uT - clean - magnet_A).norm(), 1e-9);  // magnet from 2.0 s on
  EXPECT_LT((r.samples[5].mag_uT - clean - magnet_A).norm(), 1e-9);
}

TEST(ImuSynth, GyroBiasAndScaleAsReported) {
  // Default error model: gyr - M omega - b(t) must be the white noise alone.
  ImuSynthOptions o;
  o.seed = 42;
  const SensorKinematics motion = complex_motion(10.2);
  const ImuSynthResult r = synthesize_imu(motion, uniform_times(0.05, 10.05, 80), o);
  const double sigma = o.error_model.gyr_noise_density_rad_s_sqrt_hz * std::sqrt(80.0);
  double sum_sq = 0;
  for (std::size_t k = 0; k < r.samples.size(); ++k) {
    const Vec3 omega = motion.at(1e-6 * static_cast<double>(r.samples[k].t_us)).omega_A_rad_s;
    const Vec3 residual = r.samples[k].gyr_rad_s - r.errors.gyr_scale_misalignment * omega - r.gyr_bias_rad_s[k];
    sum_sq += residual.squaredNorm();
  }
  const double rms = std::sqrt(sum_sq / (3.0 * static_cast<double>(r.samples.size())));
  EXPECT_NEAR(rms, sigma, 0.1 * sigma);  // 2400 draws: relative std of the estimate ~1.5 %
  // The bias drifts, by about the random walk over 10 s.
  const double drift = (r.gyr_bias_rad_s.back() - r.gyr_bias_rad_s.front()).norm();
  EXPECT_GT(drift, 0.0);
  EXPECT_LT(drift, 6.0 * o.error_model.gyr_bias_random_walk_rad_s_sqrt_s * std::sqrt(10.0));
  EXPECT_EQ(r.gyr_bias_rad_s.front(), r.errors.gyr_bias_rad_s);
  EXPECT_FALSE(r.errors.gyr_scale_misalignment.isIdentity());
}

namespace {

// The same motion synthesised by a sensor warming by 10 K (time constant 5 s) and by one at its
// temperature, with the given static errors, no noise and no saturation.
struct WarmAndCold {
  std::vector<double> t;
  ImuSynthResult warm, cold;
  double rise_K(std::size_t k) const { return 10.0 * (1.0 - std::exp(-(t[k] - t.front()) / 5.0)); }
};
WarmAndCold warm_and_cold(const ImuErrors& errors) {
  ImuSynthOptions o = ideal_options();
  o.errors = errors;
  o.warm_up.rise_K = 10.0;
  o.warm_up.time_constant_s = 5.0;
  o.gyr_range_rad_s = o.acc_range_m_s2 = std::numeric_limits<double>::infinity();
  const SensorKinematics motion = complex_motion(10.2);
  WarmAndCold out;
  out.t = uniform_times(0.05, 10.05, 80);
  out.warm = synthesize_imu(motion, out.t, o);
  o.warm_up.rise_K = 0.0;
  out.cold = synthesize_imu(motion, out.t, o);
  return out;
}

}  // namespace

TEST(ImuSynth, AWarmingSensorsBiasesMoveByTheirChangePerKelvin) {
  ImuErrors e;
  e.gyr_bias_per_kelvin_rad_s = Vec3(1e-3, -2e-3, 0.5e-3);
  e.acc_bias_per_kelvin_m_s2 = Vec3(0.01, 0.0, -0.02);
  const WarmAndCold r = warm_and_cold(e);
  ASSERT_EQ(r.warm.samples.size(), r.t.size());
  for (std::size_t k = 0; k < r.t.size(); ++k) {
    const double rise_K = r.rise_K(k);
    EXPECT_LT((r.warm.samples[k].gyr_rad_s - r.cold.samples[k].gyr_rad_s - rise_K * e.gyr_bias_per_kelvin_rad_s).norm(),
              1e-12);
    EXPECT_LT((r.warm.samples[k].acc_m_s2 - r.cold.samples[k].acc_m_s2 - rise_K * e.acc_bias_per_kelvin_m_s2).norm(),
              1e-12);
    EXPECT_LT((r.warm.gyr_bias_rad_s[k] - rise_K * e.gyr_bias_per_kelvin_rad_s).norm(), 1e-15);
    EXPECT_EQ(r.warm.samples[k].mag_uT, r.cold.samples[k].mag_uT);
  }
  // 8.6 K after two time constants.
  EXPECT_NEAR(r.warm.gyr_bias_rad_s.back().y(), -2e-3 * 10.0 * (1.0 - std::exp(-2.0)), 1e-12);
}

TEST(ImuSynth, AWarmingSensorsScaleFactorsChangeByTheirChangePerKelvin) {
  // Ideal otherwise: the cold signals are the true rate and specific force.
  ImuErrors e;
  e.gyr_scale_per_kelvin = Vec3(2e-4, -1e-4, 3e-4);
  e.acc_scale_per_kelvin = Vec3(-3e-4, 2e-4, 1e-4);
  const WarmAndCold r = warm_and_cold(e);
  double largest_gyr_change = 0;
  for (std::size_t k = 0; k < r.t.size(); ++k) {
    const double rise_K = r.rise_K(k);
    const Vec3 omega = r.cold.samples[k].gyr_rad_s, f = r.cold.samples[k].acc_m_s2;
    EXPECT_LT((r.warm.samples[k].gyr_rad_s - omega - rise_K * e.gyr_scale_per_kelvin.cwiseProduct(omega)).norm(),
              1e-12);
    EXPECT_LT((r.warm.samples[k].acc_m_s2 - f - rise_K * e.acc_scale_per_kelvin.cwiseProduct(f)).norm(), 1e-12);
    // A scale error is no bias: the reported true bias stays 0.
    EXPECT_EQ(r.warm.gyr_bias_rad_s[k], Vec3::Zero());
    largest_gyr_change = std::max(largest_gyr_change, (r.warm.samples[k].gyr_rad_s - omega).norm());
  }
  EXPECT_GT(largest_gyr_change, 1e-4);  // the motion turns fast enough to show it
}

TEST(ImuSynth, TheChangePerKelvinIsDrawnApartFromTheOtherErrors) {
  // The same seed gives the same turn-on biases, scales and irons with or without the
  // temperature terms, and the biases' terms with or without the scale factors' (drawn after
  // them); all are drawn at the datasheet spread (0.03 deg/s/K, 0.8 mg/K, 0.016 %/K, 0.026 %/K).
  ImuErrorModel without;
  without.gyr_bias_per_kelvin_sigma_rad_s = without.acc_bias_per_kelvin_sigma_m_s2 = 0.0;
  without.gyr_scale_per_kelvin_sigma = without.acc_scale_per_kelvin_sigma = 0.0;
  ImuErrorModel biases_only;
  biases_only.gyr_scale_per_kelvin_sigma = biases_only.acc_scale_per_kelvin_sigma = 0.0;
  double gyr_sum_sq = 0, acc_sum_sq = 0, gyr_scale_sum_sq = 0, acc_scale_sum_sq = 0;
  constexpr int kSeeds = 300;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    const ImuErrors with_terms = draw_imu_errors(ImuErrorModel(), static_cast<std::uint64_t>(seed));
    const ImuErrors plain = draw_imu_errors(without, static_cast<std::uint64_t>(seed));
    const ImuErrors with_biases = draw_imu_errors(biases_only, static_cast<std::uint64_t>(seed));
    EXPECT_EQ(with_terms.gyr_bias_rad_s, plain.gyr_bias_rad_s);
    EXPECT_EQ(with_terms.acc_scale_misalignment, plain.acc_scale_misalignment);
    EXPECT_EQ(with_terms.soft_iron, plain.soft_iron);
    EXPECT_EQ(plain.gyr_bias_per_kelvin_rad_s, Vec3::Zero());
    EXPECT_EQ(plain.gyr_scale_per_kelvin, Vec3::Zero());
    EXPECT_EQ(with_terms.gyr_bias_per_kelvin_rad_s, with_biases.gyr_bias_per_kelvin_rad_s);
    EXPECT_EQ(with_terms.acc_bias_per_kelvin_m_s2, with_biases.acc_bias_per_kelvin_m_s2);
    gyr_sum_sq += with_terms.gyr_bias_per_kelvin_rad_s.squaredNorm();
    acc_sum_sq += with_terms.acc_bias_per_kelvin_m_s2.squaredNorm();
    gyr_scale_sum_sq += with_terms.gyr_scale_per_kelvin.squaredNorm();
    acc_scale_sum_sq += with_terms.acc_scale_per_kelvin.squaredNorm();
  }
  // 900 draws each: the RMS is within 10 % of sigma (its relative std is ~2.4 %).
  EXPECT_NEAR(std::sqrt(gyr_sum_sq / (3 * kSeeds)), 0.03 * kDeg, 0.003 * kDeg);
  EXPECT_NEAR(std::sqrt(acc_sum_sq / (3 * kSeeds)), 0.8e-3 * 9.80665, 0.08e-3 * 9.80665);
  EXPECT_NEAR(std::sqrt(gyr_scale_sum_sq / (3 * kSeeds)), 1.6e-4, 0.16e-4);
  EXPECT_NEAR(std::sqrt(acc_scale_sum_sq / (3 * kSeeds)), 2.6e-4, 0.26e-4);
}

TEST(ImuSynth, SameSeedSameOutputDifferentSeedDifferent) {
  const SensorKinematics motion = complex_motion(2.0);
  const std::vector<double> t = uniform_times(0.05, 1.9, 80);
  ImuSynthOptions o;
  o.disturbances.push_back({MagDisturbance::Kind::kTransient, 1.0, 0.2, Vec3(10, 0, 0)});
  o.seed = 7;
  const ImuSynthResult a = synthesize_imu(motion, t, o);
  const ImuSynthResult b = synthesize_imu(motion, t, o);
  o.seed = 8;
  const ImuSynthResult c = synthesize_imu(motion, t, o);
  ASSERT_EQ(a.samples.size(), b.samples.size());
  bool any_different = false;
  for (std::size_t k = 0; k < a.samples.size(); ++k) {
    EXPECT_EQ(a.samples[k].t_us, b.samples[k].t_us);
    EXPECT_EQ(a.samples[k].gyr_rad_s, b.samples[k].gyr_rad_s);
    EXPECT_EQ(a.samples[k].acc_m_s2, b.samples[k].acc_m_s2);
    EXPECT_EQ(a.samples[k].mag_uT, b.samples[k].mag_uT);
    any_different = any_different || a.samples[k].gyr_rad_s != c.samples[k].gyr_rad_s;
  }
  EXPECT_TRUE(any_different);
  EXPECT_FALSE(a.errors.hard_iron_uT.isApprox(c.errors.hard_iron_uT));
}

TEST(ImuSynth, BatchesRoundTrip) {
  const SensorKinematics motion = complex_motion(2.0);
  const ImuSynthResult r = synthesize_imu(motion, uniform_times(0.05, 1.9, 80), ImuSynthOptions());
  ASSERT_EQ(r.samples.size(), 149u);
  const auto batches = imu_batches("arm_right", r.samples, 32);
  ASSERT_EQ(batches.size(), 5u);
  std::size_t k = 0;
  for (const auto& batch : batches) {
    EXPECT_EQ(batch.device_id(), "arm_right");
    for (const auto& s : posefuse::session::samples_from_batch(batch)) {
      EXPECT_EQ(s.t_us, r.samples[k].t_us);
      EXPECT_NEAR((s.gyr_rad_s - r.samples[k].gyr_rad_s).norm(), 0.0, 1e-5);
      ++k;
    }
  }
  EXPECT_EQ(k, r.samples.size());
  posefuse::imu::validate_imu_stream(r.samples, "synth");
}

TEST(ImuSynth, RejectsBadInput) {
  const SensorKinematics motion = complex_motion(2.0);
  EXPECT_THROW(synthesize_imu(motion, {0.5, 0.5}, ImuSynthOptions()), Error);
  EXPECT_THROW(synthesize_imu(motion, {0.5, std::nan("")}, ImuSynthOptions()), Error);
  try {
    synthesize_imu(motion, {5.0}, ImuSynthOptions());
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), posefuse::ErrorCode::kOutOfRange);
  }
  ImuSynthOptions o;
  o.error_model.mag_noise_uT = -1;
  EXPECT_THROW(synthesize_imu(motion, {0.5}, o), Error);
  o = ImuSynthOptions();
  o.earth_field.dip_rad = pi / 2;
  EXPECT_THROW(synthesize_imu(motion, {0.5}, o), Error);
  o = ImuSynthOptions();
  ImuErrors e;
  e.soft_iron(0, 1) = 0.5;  // not symmetric
  o.errors = e;
  EXPECT_THROW(synthesize_imu(motion, {0.5}, o), Error);
  o = ImuSynthOptions();
  o.disturbances.push_back({MagDisturbance::Kind::kTransient, 1.0, 0.0, Vec3(1, 0, 0)});
  EXPECT_THROW(synthesize_imu(motion, {0.5}, o), Error);
  const auto field_of = [&](const ImuSynthOptions& bad) {
    try {
      synthesize_imu(motion, {0.5}, bad);
    } catch (const Error& error) {
      return error.field();
    }
    return std::string("no error");
  };
  o = ImuSynthOptions();
  o.warm_up.rise_K = -1;
  EXPECT_EQ(field_of(o), "options.warm_up.rise_K");
  o = ImuSynthOptions();
  o.warm_up.time_constant_s = 0;
  EXPECT_EQ(field_of(o), "options.warm_up.time_constant_s");
  o = ImuSynthOptions();
  o.error_model.gyr_bias_per_kelvin_sigma_rad_s = std::nan("");
  EXPECT_EQ(field_of(o), "error_model.gyr_bias_per_kelvin_sigma_rad_s");
  o = ImuSynthOptions();
  o.error_model.acc_scale_per_kelvin_sigma = -1e-4;
  EXPECT_EQ(field_of(o), "error_model.acc_scale_per_kelvin_sigma");
}

TEST(SensorKinematics, RejectsBadTrajectories) {
  SensorTrajectory t = sample_trajectory(complex_position, complex_orientation, 0, 0.1);
  SensorTrajectory bad = t;
  bad.dt_s = 0;
  EXPECT_THROW(SensorKinematics{bad}, Error);
  bad = t;
  bad.W_from_A.pop_back();
  EXPECT_THROW(SensorKinematics{bad}, Error);
  bad = t;
  bad.p_W_m[3].x() = std::nan("");
  EXPECT_THROW(SensorKinematics{bad}, Error);
  bad = t;
  bad.W_from_A[3].coeffs() *= 2.0;
  EXPECT_THROW(SensorKinematics{bad}, Error);
  bad = t;
  bad.W_from_A[5] = rot(2.0, Vec3::UnitX()) * bad.W_from_A[5];
  EXPECT_THROW(SensorKinematics{bad}, Error);
  bad = t;
  bad.p_W_m.resize(5);
  bad.W_from_A.resize(5);
  EXPECT_THROW(SensorKinematics{bad}, Error);
}
