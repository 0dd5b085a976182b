#pragma once
// Every buzzer stop in a long stream of camera audio, with bounded memory.
//
// Paper 1 (II-G.1) buzzes once, near the start; a buzzer that stops again later in the session
// (e.g. at its end) makes the base IMU's drift against the camera observable. The BUZZER_STOP
// events come on the base IMU's clock and may reach the stream long before or after their sound
// (chunks are merged by each stream's own timestamps), so the audio is not kept: the scanner
// keeps only the last `window_s` of it, looks for a stop once per `scan_every_s` of new audio,
// and remembers the stops it heard. A stop is found when at least scan_every_s + margin_s of
// silence follows it (the detector takes the last stop of a window and needs the tone off at the
// window's end). Pairing a stop with its event is the caller's (by the time the clocks predict).
#include <optional>
#include <vector>

#include "sync/buzzer_stop.hpp"
#include "sync/tone_search.hpp"

namespace posefuse::sync {

struct ToneStopScannerOptions {
  BuzzerStopOptions detector;
  double window_s = 4.0;      // audio kept; must hold a stop with min_on_s before and margin_s after
  double scan_every_s = 0.5;  // new audio between two scans
  double margin_s = 0.2;      // a stop is taken only this far before the window's end (silence after it)
  double merge_s = 0.25;      // stops this close are the same stop seen by two scans
  // The tone's frequency measured, not given (detector.tone_hz unused until found): each scan
  // first searches tone_search's band of the window for a tone that sounds and stops
  // (tone_search.hpp); the first found is kept for the rest of the stream. Why measure even a
  // known buzzer (a narrow band around its nominal frequency): the stop detector demodulates at
  // detector.tone_hz, and a tone 50 / 100 / 150 Hz away from it puts its stop 0.2 / 0.9 / 1.9 ms
  // late or early with an unchanged reported sigma of tens of microseconds (bench_buzzer_stop);
  // piezo buzzers are specified to a few percent.
  bool find_tone = false;
  ToneSearchOptions tone_search;
};

class ToneStopScanner {
 public:
  // Throws posefuse::Error kInvalidArgument "sample_rate_hz" / "options.*" for bad values.
  explicit ToneStopScanner(double sample_rate_hz, const ToneStopScannerOptions& options = {});

  // Mono samples starting at t0_camera_us (finite, else kInvalidArgument "audio.t_us"). Audio
  // that does not continue the last call's (a gap, an overlap, a step back) restarts the window:
  // no stop is searched across the break.
  void add(double t0_camera_us, const std::vector<std::int16_t>& samples);

  const std::vector<BuzzerStop>& stops() const { return stops_; }  // in time order
  // The tone searched for: detector.tone_hz, or with find_tone the one found (nullopt before).
  std::optional<double> tone_hz() const;
  // With find_tone, before the tone is found: a tone that sounds and stops heard outside the band
  // searched (500-8000 Hz, the latest), for telling the user which frequency to configure.
  const std::optional<double>& heard_outside_hz() const { return heard_outside_hz_; }

 private:
  void scan();

  ToneStopScannerOptions options_;
  AudioPcm window_;
  std::size_t new_samples_ = 0;  // since the last scan
  std::vector<BuzzerStop> stops_;
  bool tone_found_ = false;
  std::optional<double> heard_outside_hz_;
  std::size_t scans_without_tone_ = 0;
};

}  // namespace posefuse::sync
