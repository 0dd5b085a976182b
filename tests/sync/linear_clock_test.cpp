// Clock offsets and drift from synthetic BLE receipts with quantisation, jitter, losses and late
// outliers.
//
// Bounds: each stamp is quantised to the 312.5 us BLE tick, so one observation has sigma
// 312.5 / sqrt(6) = 128 us. With ~500 inliers spread over 600 s the offset at the centre has
// sigma ~128 / sqrt(500) = 6 us and the drift sigma ~128 us / (sqrt(500) * 173 s) = 0.03 ppm,
// so a mapped time is good to ~15 us even at the session ends. We allow 50 us (and 4 reported
// sigmas) for mapped times and 0.2 ppm for the drift.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "../imu/expect_error.hpp"
#include "sync/broadcast_offsets.hpp"
#include "sync/linear_clock.hpp"

namespace posefuse::sync {
namespace {

using posefuse::testing::expect_error;

struct TrueClock {
  double offset_us;
  double drift;
  double read(double true_us) const { return true_us * (1.0 + drift) + offset_us; }
  double invert(double device_us) const { return (device_us - offset_us) / (1.0 + drift); }
};

double quantise(double t_us, double tick) { return std::floor(t_us / tick) * tick; }

// Broadcasts once a second for 600 s; each device loses 10% and stamps 5% late by 2..20 ms.
std::vector<BroadcastReceipt> receipts(const TrueClock& arm, const TrueClock& base, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<BroadcastReceipt> out;
  for (int k = 0; k < 600; ++k) {
    const double t_true = 1e6 * k + 250'000.0 * u(rng);
    for (const auto& [name, clock] : {std::pair{"arm", arm}, std::pair{"base", base}}) {
      if (u(rng) < 0.10) continue;
      double t = clock.read(t_true) + 20.0 * (u(rng) - 0.5);  // radio jitter, well below a tick
      if (u(rng) < 0.05) t += 2000.0 + 18000.0 * u(rng);
      out.push_back({k, name, quantise(t, kBleClockTickUs)});
    }
  }
  return out;
}

TEST(LinearClock, OffsetAndDriftFromBroadcastsWithOutliers) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const TrueClock arm{-3.2e6 + 1000.0 * seed, 40e-6};
    const TrueClock base{7.7e6, -25e-6};
    const auto obs = broadcast_observations(receipts(arm, base, seed), "arm", "base");
    const ClockFit fit = fit_linear_clock(obs);
    EXPECT_GT(fit.inlier_count, 400);
    EXPECT_LT(fit.inlier_count, static_cast<int>(obs.size()));  // late stamps were rejected
    const double true_drift = (1.0 + base.drift) / (1.0 + arm.drift) - 1.0;
    EXPECT_NEAR(fit.clock.drift, true_drift, 0.2e-6) << "seed " << seed;
    for (double t_true : {0.0, 150e6, 300e6, 450e6, 600e6}) {
      const double t_arm = arm.read(t_true);
      const double error = fit.clock.to_reference_us(t_arm) - base.read(t_true);
      EXPECT_LT(std::abs(error), 50.0) << "seed " << seed << " t " << t_true;
      EXPECT_LT(std::abs(error), 4.0 * fit.clock.sigma_us(t_arm) + 1.0) << "seed " << seed;
    }
  }
}

TEST(LinearClock, SingleEventGivesOffsetWithGrowingUncertainty) {
  const ClockFit fit = fit_linear_clock({{1e6, 4e6, 100.0}}, {.drift_prior_sigma = 50e-6});
  EXPECT_NEAR(fit.clock.to_reference_us(1e6), 4e6, 1e-6);
  EXPECT_NEAR(fit.clock.drift, 0.0, 1e-12);
  EXPECT_NEAR(fit.clock.sigma_us(1e6), 100.0, 1e-6);
  // 600 s away the 50 ppm prior adds 30 ms of uncertainty.
  EXPECT_NEAR(fit.clock.sigma_us(601e6), std::hypot(100.0, 30000.0), 1.0);
}

TEST(LinearClock, TwoBuzzerEventsGiveDrift) {
  // Buzzer at the start and at the end of a 10-minute session; camera runs 30 ppm fast.
  const TrueClock camera{0.0, 30e-6};
  std::vector<ClockObservation> obs = {{5e6, camera.read(5e6) + 40.0, 80.0}, {605e6, camera.read(605e6) - 30.0, 80.0}};
  const ClockFit fit = fit_linear_clock(obs);
  EXPECT_NEAR(fit.clock.drift, 30e-6, 0.3e-6);
  EXPECT_NEAR(fit.clock.to_reference_us(305e6), camera.read(305e6), 100.0);
}

TEST(LinearClock, HostReceiptsLowerEnvelope) {
  // The host stamps each packet 2 ms + an exponential latency (mean 5 ms) after the device.
  const TrueClock device{-1.5e6, 60e-6};
  std::mt19937 rng(7);
  std::exponential_distribution<double> latency(1.0 / 5000.0);
  std::vector<ClockObservation> obs;
  for (int k = 0; k < 6000; ++k) {
    const double t_true = 1e5 * k;
    obs.push_back({device.read(t_true), t_true + 2000.0 + latency(rng), 0.0});
  }
  const ClockFit fit = fit_linear_clock(lower_envelope(obs, 10e6));
  const double true_drift = 1.0 / (1.0 + device.drift) - 1.0;
  EXPECT_NEAR(fit.clock.drift, true_drift, 0.5e-6);
  for (double t_true : {0.0, 300e6, 599e6}) {
    // The fitted map includes the 2 ms minimum latency; the residual latency of the minimum of
    // 100 exponential draws is ~50 us.
    EXPECT_NEAR(fit.clock.to_reference_us(device.read(t_true)), t_true + 2000.0, 300.0);
  }
}

TEST(LinearClock, ComposeEqualsChainedMaps) {
  LinearClock inner{1e6, 2500.0, 30e-6, Eigen::Matrix2d::Zero()};
  inner.covariance.diagonal() << 100.0, 1e-14;
  LinearClock outer{4e6, -7000.0, -20e-6, Eigen::Matrix2d::Zero()};
  outer.covariance.diagonal() << 400.0, 4e-14;
  const LinearClock both = compose(outer, inner);
  for (double t : {0.0, 1e6, 3e8}) {
    EXPECT_NEAR(both.to_reference_us(t), outer.to_reference_us(inner.to_reference_us(t)), 1e-6);
    EXPECT_GE(both.sigma_us(t) + 1e-9, inner.sigma_us(t));
  }
  EXPECT_NEAR(both.sigma_us(1e6), std::sqrt(100.0 + 400.0 + 9e12 * 4e-14), 1e-3);
}

TEST(LinearClock, RefusesBadInput) {
  expect_error([] { fit_linear_clock({}); }, ErrorCode::kInvalidArgument, "observations");
  expect_error(
      [] {
        fit_linear_clock({{0, 1, 1}, {NAN, 1, 1}});
      },
      ErrorCode::kInvalidArgument, "observations[1].device_us");
  expect_error([] { fit_linear_clock({{0, 1, -1}}); }, ErrorCode::kInvalidArgument, "observations[0].sigma_us");
  expect_error(
      [] {
        broadcast_observations({{1, "arm", 5.0}, {1, "arm", 6.0}}, "arm", "base");
      },
      ErrorCode::kInvalidArgument, "receipts[1].broadcast_id");
  expect_error(
      [] {
        broadcast_observations({{1, "arm", 5.0}, {2, "base", 6.0}}, "arm", "base");
      },
      ErrorCode::kFailedPrecondition, "receipts");
  expect_error(
      [] {
        broadcast_observations({{1, "arm", INFINITY}}, "arm", "base");
      },
      ErrorCode::kInvalidArgument, "receipts[0].t_device_us");
  expect_error([] { lower_envelope({{0, 1, 1}}, 0.0); }, ErrorCode::kInvalidArgument, "bin_us");
  expect_error([] { fit_linear_clock({{0, 1, 1}}, {.max_iterations = 0}); }, ErrorCode::kInvalidArgument, "options");
}

}  // namespace
}  // namespace posefuse::sync
