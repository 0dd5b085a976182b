// ToneStopScanner on a long synthetic recording: 1 s tones stopping at known, off-grid instants
// in white noise, fed in 0.1 s chunks as a camera streams them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "common/error.hpp"
#include "sync/tone_stop_scanner.hpp"

namespace posefuse::sync {
namespace {

constexpr double kRateHz = 16000.0;

// Noise everywhere, a tone (2.7 kHz unless said) in the second before each stop.
std::vector<std::int16_t> recording(double duration_s, const std::vector<double>& stops_s, unsigned seed,
                                    double tone_hz = 2700.0) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 300.0);
  std::vector<std::int16_t> samples(static_cast<std::size_t>(duration_s * kRateHz));
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const double t = static_cast<double>(k) / kRateHz;
    double x = noise(rng);
    for (const double stop : stops_s) {
      if (t >= stop - 1.0 && t < stop) x += 8000.0 * std::sin(2.0 * std::numbers::pi * tone_hz * t);
    }
    samples[k] = static_cast<std::int16_t>(std::clamp(x, -32768.0, 32767.0));
  }
  return samples;
}

void feed(ToneStopScanner& scanner, const std::vector<std::int16_t>& samples, double t0_us, std::size_t chunk) {
  for (std::size_t first = 0; first < samples.size(); first += chunk) {
    const std::size_t end = std::min(samples.size(), first + chunk);
    scanner.add(t0_us + 1e6 * static_cast<double>(first) / kRateHz,
                std::vector<std::int16_t>(samples.begin() + static_cast<std::ptrdiff_t>(first),
                                          samples.begin() + static_cast<std::ptrdiff_t>(end)));
  }
}

TEST(ToneStopScanner, FindsEveryStopOnceAndNothingInNoise) {
  // Two stops 1.7 s apart (0.7 s of silence between them, the least the default scan needs).
  const std::vector<double> stops_s = {3.00021, 17.31307, 19.0131, 44.9999};
  const std::vector<std::int16_t> audio = recording(50.0, stops_s, 3);
  ToneStopScanner scanner(kRateHz);
  const double t0_us = 1'234'567.0;
  feed(scanner, audio, t0_us, 1600);
  ASSERT_EQ(scanner.stops().size(), stops_s.size());
  for (std::size_t k = 0; k < stops_s.size(); ++k) {
    // The detector's own bound at 16 kHz (tests/sync/buzzer_stop_test.cpp): 0.3 ms.
    EXPECT_NEAR(scanner.stops()[k].t_camera_us, t0_us + 1e6 * stops_s[k], 300.0) << k;
  }
  ToneStopScanner quiet(kRateHz);
  feed(quiet, recording(30.0, {}, 4), 0.0, 1600);
  EXPECT_TRUE(quiet.stops().empty());
}

TEST(ToneStopScanner, ABreakInTheAudioRestartsTheWindow) {
  const std::vector<std::int16_t> audio = recording(12.0, {5.5}, 5);
  ToneStopScanner scanner(kRateHz);
  // The tone's first half, then the audio jumps by 10 s: the stop before the jump is not heard
  // (its silence never came), the audio after it is scanned afresh.
  const auto half = static_cast<std::ptrdiff_t>(5.0 * kRateHz);
  feed(scanner, std::vector<std::int16_t>(audio.begin(), audio.begin() + half), 0.0, 1600);
  feed(scanner, recording(8.0, {4.0}, 6), 20e6, 1600);
  ASSERT_EQ(scanner.stops().size(), 1u);
  EXPECT_NEAR(scanner.stops()[0].t_camera_us, 24e6, 300.0);
}

// A buzzer at 3.41 kHz, not the default: with find_tone the scanner finds the tone in the first
// window that holds a stop and then hears the same stops as a scanner told the frequency.
TEST(ToneStopScanner, FindsAnUnknownToneAndTheSameStops) {
  const double tone_hz = 3410.0;
  const std::vector<double> stops_s = {4.20013, 13.77771, 25.5};
  const std::vector<std::int16_t> audio = recording(30.0, stops_s, 7, tone_hz);
  ToneStopScannerOptions told;
  told.detector.tone_hz = tone_hz;
  ToneStopScanner known(kRateHz, told);
  ToneStopScannerOptions searching;
  searching.find_tone = true;
  ToneStopScanner unknown(kRateHz, searching);
  EXPECT_FALSE(unknown.tone_hz().has_value());
  feed(known, audio, 0.0, 1600);
  feed(unknown, audio, 0.0, 1600);
  ASSERT_TRUE(unknown.tone_hz().has_value());
  EXPECT_NEAR(*unknown.tone_hz(), tone_hz, 5.0);
  ASSERT_EQ(known.stops().size(), stops_s.size());
  ASSERT_EQ(unknown.stops().size(), stops_s.size());
  for (std::size_t k = 0; k < stops_s.size(); ++k) {
    EXPECT_NEAR(unknown.stops()[k].t_camera_us, 1e6 * stops_s[k], 300.0) << k;
    EXPECT_NEAR(unknown.stops()[k].t_camera_us, known.stops()[k].t_camera_us, 50.0) << k;
  }
}

// Searching within 10 % of 2700 Hz, a 4 kHz buzzer is not taken, but named for the error message:
// at any scan in the first 30 s of audio, later at one scan per window.
TEST(ToneStopScanner, NamesAToneThatStopsOutsideItsBand) {
  for (const double stop_s : {3.0, 45.2}) {
    ToneStopScannerOptions options;
    options.find_tone = true;
    options.tone_search.min_hz = 2430.0;
    options.tone_search.max_hz = 2970.0;
    ToneStopScanner scanner(kRateHz, options);
    feed(scanner, recording(stop_s + 5.0, {stop_s}, 9, 4000.0), 0.0, 1600);
    EXPECT_FALSE(scanner.tone_hz().has_value()) << stop_s;
    EXPECT_TRUE(scanner.stops().empty()) << stop_s;
    ASSERT_TRUE(scanner.heard_outside_hz().has_value()) << stop_s;
    EXPECT_NEAR(*scanner.heard_outside_hz(), 4000.0, 5.0) << stop_s;
  }
}

TEST(ToneStopScanner, BadRateOrOptionsAreRejected) {
  EXPECT_THROW(ToneStopScanner(0.0), Error);
  EXPECT_THROW(ToneStopScanner(std::nan("")), Error);
  ToneStopScannerOptions options;
  options.window_s = 0.6;  // cannot hold a scan interval plus the margin and the tone
  EXPECT_THROW(ToneStopScanner(kRateHz, options), Error);
  ToneStopScannerOptions above_nyquist;
  above_nyquist.detector.tone_hz = 9000.0;  // 16 kHz audio
  EXPECT_THROW(ToneStopScanner(kRateHz, above_nyquist), Error);
  ToneStopScannerOptions bad_search;
  bad_search.find_tone = true;
  bad_search.tone_search.min_hz = 9000.0;
  EXPECT_THROW(ToneStopScanner(kRateHz, bad_search), Error);
  ToneStopScanner scanner(kRateHz);
  EXPECT_THROW(scanner.add(std::nan(""), {1, 2, 3}), Error);
}

}  // namespace
}  // namespace posefuse::sync
