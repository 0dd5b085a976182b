// find_stopping_tone on synthetic audio: a buzzer among a continuous whistle, hum, noise, clicks
// and a noise burst, at several rates and tone frequencies.
#include "sync/tone_search.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "common/error.hpp"

namespace posefuse::sync {
namespace {

struct Scene {
  double rate_hz = 48000.0;
  double duration_s = 3.0;
  double tone_hz = 0.0;  // 0: no buzzer
  double tone_on_s = 0.5, tone_off_s = 1.7;
  double tone_amplitude = 4000.0;
  double whistle_hz = 0.0;  // a tone that never stops (a fan, a monitor's whine)
  double whistle_amplitude = 6000.0;
  double noise_sigma = 300.0;
  bool clicks = false;       // a 1 ms full-scale click every 0.4 s
  bool noise_burst = false;  // broadband noise, 10x louder, from 1.0 to 2.0 s
};

AudioPcm render(const Scene& scene, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, scene.noise_sigma);
  AudioPcm audio;
  audio.sample_rate_hz = scene.rate_hz;
  audio.samples.resize(static_cast<std::size_t>(scene.duration_s * scene.rate_hz));
  for (std::size_t k = 0; k < audio.samples.size(); ++k) {
    const double t = static_cast<double>(k) / scene.rate_hz;
    double x = noise(rng) + 3000.0 * std::sin(2.0 * std::numbers::pi * 50.0 * t);  // mains hum
    if (scene.tone_hz > 0.0 && t >= scene.tone_on_s && t < scene.tone_off_s) {
      x += scene.tone_amplitude * std::sin(2.0 * std::numbers::pi * scene.tone_hz * t + 0.7);
    }
    if (scene.whistle_hz > 0.0) x += scene.whistle_amplitude * std::sin(2.0 * std::numbers::pi * scene.whistle_hz * t);
    if (scene.clicks && std::fmod(t, 0.4) < 0.001) x += 30000.0;
    if (scene.noise_burst && t >= 1.0 && t < 2.0) x += 10.0 * noise(rng);
    audio.samples[k] = static_cast<std::int16_t>(std::clamp(x, -32768.0, 32767.0));
  }
  return audio;
}

TEST(ToneSearch, FindsTheBuzzerAtSeveralRatesAndFrequencies) {
  unsigned seed = 1;
  for (const double rate : {16000.0, 44100.0, 48000.0}) {
    for (const double tone : {812.5, 2700.0, 4123.0, 6999.0}) {
      if (tone >= rate / 2.0) continue;
      Scene scene;
      scene.rate_hz = rate;
      scene.tone_hz = tone;
      const std::optional<FoundTone> found = find_stopping_tone(render(scene, seed++));
      ASSERT_TRUE(found.has_value()) << rate << " Hz audio, " << tone << " Hz tone";
      // A few Hz: the stop detector demodulates over 5 ms, where 5 Hz turns the phase by 9 deg.
      EXPECT_NEAR(found->hz, tone, 5.0) << rate << " Hz audio";
      EXPECT_GT(found->on_to_off_ratio, 4.0);
      EXPECT_GT(found->peak_to_band_ratio, 4.0);
    }
  }
}

// A louder whistle that never stops, clicks and hum: the buzzer is the tone that stops.
TEST(ToneSearch, TheToneThatStopsWinsOverALouderOneThatDoesNot) {
  Scene scene;
  scene.tone_hz = 3300.0;
  scene.whistle_hz = 2200.0;
  scene.whistle_amplitude = 12000.0;
  scene.clicks = true;
  const std::optional<FoundTone> found = find_stopping_tone(render(scene, 11));
  ASSERT_TRUE(found.has_value());
  EXPECT_NEAR(found->hz, 3300.0, 5.0);
}

TEST(ToneSearch, NothingWithoutAToneThatSoundsAndStops) {
  Scene quiet;  // noise and hum only
  EXPECT_FALSE(find_stopping_tone(render(quiet, 21)).has_value());
  Scene whistle;  // a tone that never stops
  whistle.whistle_hz = 2700.0;
  EXPECT_FALSE(find_stopping_tone(render(whistle, 22)).has_value());
  Scene burst;  // loud broadband noise that starts and stops
  burst.noise_burst = true;
  EXPECT_FALSE(find_stopping_tone(render(burst, 23)).has_value());
  Scene clicks;  // full-scale clicks: broadband, and only a frame each
  clicks.clicks = true;
  EXPECT_FALSE(find_stopping_tone(render(clicks, 24)).has_value());
  Scene outside;  // the buzzer above the searched band
  outside.tone_hz = 9500.0;
  EXPECT_FALSE(find_stopping_tone(render(outside, 25)).has_value());
  Scene short_audio;  // fewer than four frames
  short_audio.duration_s = 0.05;
  short_audio.tone_hz = 2700.0;
  short_audio.tone_on_s = 0.0;
  short_audio.tone_off_s = 0.03;
  EXPECT_FALSE(find_stopping_tone(render(short_audio, 26)).has_value());
}

TEST(ToneSearch, RefusesBadRateAndOptions) {
  AudioPcm audio;
  audio.samples.assign(48000, 0);
  audio.sample_rate_hz = 0.0;
  EXPECT_THROW(find_stopping_tone(audio), Error);
  audio.sample_rate_hz = 48000.0;
  EXPECT_THROW(find_stopping_tone(audio, {.min_hz = 3000.0, .max_hz = 2000.0}), Error);
  EXPECT_THROW(find_stopping_tone(audio, {.min_hz = 30000.0, .max_hz = 40000.0}), Error);
  EXPECT_THROW(find_stopping_tone(audio, {.frame_s = 0.0}), Error);
  EXPECT_THROW(find_stopping_tone(audio, {.min_on_to_off_ratio = 1.0}), Error);
  try {
    find_stopping_tone(audio, {.min_hz = 30000.0, .max_hz = 40000.0});
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("Nyquist"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace posefuse::sync
