// Buzzer-stop detection on synthetic audio: a tone that stops at a known, off-grid instant, in
// white noise, at several sample rates.
//
// Bound: with tone amplitude A, noise sigma_n and an envelope window of L samples, the envelope
// noise is about sigma_n * sqrt(2 / L) and the edge ramp falls by A per window, so the noise
// part of the edge error is about sigma_n / A * sqrt(2 / L) * window: <= 0.11 ms for A = 8000,
// sigma_n = 800 and a 5 ms window (L >= 40). On top come the sample grid (half a sample, 62 us
// at 8 kHz) and the mirror-frequency bias (<= 1 / (2 sin omega) samples, 74 us for 2.7 kHz at
// 8 kHz): ~0.25 ms worst case at 8 kHz, less at higher rates. We allow 0.3 ms, still below one
// BLE clock tick (0.3125 ms) and 1% of a 30 Hz depth frame, and also require the error within
// 4 reported sigmas.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "../imu/expect_error.hpp"
#include "sync/buzzer_stop.hpp"

namespace posefuse::sync {
namespace {

using posefuse::testing::expect_error;

AudioPcm tone_that_stops(double rate_hz, double tone_hz, double t0_us, double stop_us, double duration_s,
                         double amplitude, double noise_sigma, unsigned seed) {
  AudioPcm audio;
  audio.t0_camera_us = t0_us;
  audio.sample_rate_hz = rate_hz;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_sigma);
  const auto n = static_cast<std::size_t>(duration_s * rate_hz);
  for (std::size_t k = 0; k < n; ++k) {
    const double t_us = t0_us + static_cast<double>(k) * 1e6 / rate_hz;
    double x = noise(rng);
    if (t_us < stop_us) x += amplitude * std::sin(2.0 * std::numbers::pi * tone_hz * t_us * 1e-6 + 0.3);
    audio.samples.push_back(static_cast<std::int16_t>(std::clamp(x, -32768.0, 32767.0)));
  }
  return audio;
}

TEST(BuzzerStop, RecoversStopTimeAtSeveralRates) {
  for (double rate : {8000.0, 16000.0, 44100.0, 48000.0}) {
    for (unsigned seed = 1; seed <= 5; ++seed) {
      const double t0 = 1'000'000.0 + 37.0 * seed;
      const double stop = t0 + 400'000.0 + 13.7 * seed;  // off the sample grid
      const AudioPcm audio = tone_that_stops(rate, 2700.0, t0, stop, 0.8, 8000.0, 800.0, seed);
      const BuzzerStop found = detect_buzzer_stop(audio);
      const double error = found.t_camera_us - stop;
      EXPECT_LT(std::abs(error), 300.0) << "rate " << rate << " seed " << seed;
      EXPECT_LT(std::abs(error), 4.0 * found.sigma_us) << "rate " << rate << " seed " << seed;
      EXPECT_GT(found.sigma_us, 0.0);
      EXPECT_LT(found.sigma_us, 300.0);
      EXPECT_GT(found.on_level, 10.0 * found.off_level);
    }
  }
}

TEST(BuzzerStop, NoiseFreeEdgeWithinHalfASample) {
  // Sampled data cannot tell where between the last tone sample and the first silent one the
  // tone stopped (half a sample either way), and the truncated tone's mirror frequency shifts
  // the envelope's half-level crossing by up to 1 / (2 sin omega) samples (see
  // detect_buzzer_stop). Both are fractions of a sample here: 125 / 75 / 51 us at 8 / 16 / 48 kHz.
  for (double rate : {8000.0, 16000.0, 48000.0}) {
    for (double frac : {0.1, 0.5, 0.9}) {
      const double stop = 500'000.0 + frac * 1e6 / rate;
      const AudioPcm audio = tone_that_stops(rate, 2000.0, 0.0, stop, 1.0, 10000.0, 0.0, 1);
      const BuzzerStop found = detect_buzzer_stop(audio, {.tone_hz = 2000.0});
      const double omega = 2.0 * std::numbers::pi * 2000.0 / rate;
      const double bound_us = (0.5 + 0.5 / std::sin(omega)) * 1e6 / rate;
      EXPECT_LE(std::abs(found.t_camera_us - stop), bound_us) << rate << " " << frac;
      EXPECT_LE(std::abs(found.t_camera_us - stop), 3.0 * found.sigma_us) << rate << " " << frac;
    }
  }
}

TEST(BuzzerStop, OffsetFromBaseImuStopTime) {
  const AudioPcm audio = tone_that_stops(16000.0, 2700.0, 5e6, 5.3e6, 0.6, 8000.0, 400.0, 3);
  const BuzzerStop found = detect_buzzer_stop(audio);
  // The base IMU stamped the stop at 123456 us on its own clock.
  const ClockObservation ob = buzzer_observation(found, 123456.0, 50.0);
  EXPECT_NEAR(ob.reference_us - ob.device_us, 5.3e6 - 123456.0, 300.0);
  EXPECT_GE(ob.sigma_us, 50.0);
}

TEST(BuzzerStop, RefusesAudioWithoutAStop) {
  // Silence only.
  expect_error([] { detect_buzzer_stop(tone_that_stops(16000.0, 2700.0, 0, -1, 0.5, 8000, 300, 1)); },
               ErrorCode::kFailedPrecondition, "audio.buzzer");
  // Tone that never stops.
  expect_error([] { detect_buzzer_stop(tone_that_stops(16000.0, 2700.0, 0, 1e9, 0.5, 8000, 300, 1)); },
               ErrorCode::kFailedPrecondition, "audio.buzzer");
  // Tone at another frequency: at 2700 Hz nothing stops above the noise.
  expect_error([] { detect_buzzer_stop(tone_that_stops(16000.0, 1000.0, 0, 2.5e5, 0.5, 8000, 300, 1)); },
               ErrorCode::kFailedPrecondition, "audio.buzzer");
}

TEST(BuzzerStop, RefusesBadInput) {
  AudioPcm audio = tone_that_stops(16000.0, 2700.0, 0, 2.5e5, 0.5, 8000, 300, 1);
  AudioPcm bad = audio;
  bad.sample_rate_hz = 0.0;
  expect_error([&] { detect_buzzer_stop(bad); }, ErrorCode::kInvalidArgument, "audio.sample_rate_hz");
  bad = audio;
  bad.samples.clear();
  expect_error([&] { detect_buzzer_stop(bad); }, ErrorCode::kInvalidArgument, "audio.samples");
  bad = audio;
  bad.t0_camera_us = NAN;
  expect_error([&] { detect_buzzer_stop(bad); }, ErrorCode::kInvalidArgument, "audio.t0_camera_us");
  expect_error([&] { detect_buzzer_stop(audio, {.tone_hz = 9000.0}); }, ErrorCode::kInvalidArgument, "options.tone_hz");
  bad.samples.assign(100, 0);
  bad.t0_camera_us = 0;
  expect_error([&] { detect_buzzer_stop(bad); }, ErrorCode::kFailedPrecondition, "audio.samples");
}

}  // namespace
}  // namespace posefuse::sync
