#include "sync/tone_stop_scanner.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.hpp"

namespace posefuse::sync {

namespace {
constexpr double kOutsideEveryScanS = 30.0;
}  // namespace

ToneStopScanner::ToneStopScanner(double sample_rate_hz, const ToneStopScannerOptions& options) : options_(options) {
  if (!std::isfinite(sample_rate_hz) || sample_rate_hz <= 0.0) {
    throw_invalid("sample_rate_hz", "must be > 0, got " + std::to_string(sample_rate_hz));
  }
  const ToneStopScannerOptions& o = options;
  if (!(o.scan_every_s > 0.0) || !(o.margin_s >= 0.0) || !(o.merge_s >= 0.0) ||
      !(o.window_s >= o.scan_every_s + o.margin_s + o.detector.min_on_s)) {
    throw_invalid("options",
                  "need scan_every_s > 0, margin_s and merge_s >= 0, and window_s >= "
                  "scan_every_s + margin_s + detector.min_on_s");
  }
  window_.sample_rate_hz = sample_rate_hz;
  if (o.find_tone) {
    validate_tone_search(o.tone_search, sample_rate_hz);
  } else if (!(o.detector.tone_hz > 0.0) || !(o.detector.tone_hz < sample_rate_hz / 2.0)) {
    throw_invalid("options.detector.tone_hz", "must be in (0, " + std::to_string(sample_rate_hz / 2.0) +
                                                  ") Hz (the Nyquist frequency), got " +
                                                  std::to_string(o.detector.tone_hz));
  }
}

std::optional<double> ToneStopScanner::tone_hz() const {
  if (options_.find_tone && !tone_found_) return std::nullopt;
  return options_.detector.tone_hz;
}

void ToneStopScanner::add(double t0_camera_us, const std::vector<std::int16_t>& samples) {
  if (!std::isfinite(t0_camera_us)) throw_invalid("audio.t_us", "not finite");
  const double period_us = 1e6 / window_.sample_rate_hz;
  const double expected_us = window_.t0_camera_us + static_cast<double>(window_.samples.size()) * period_us;
  if (!window_.samples.empty() && std::abs(t0_camera_us - expected_us) > 0.5 * period_us) {
    window_.samples.clear();  // not contiguous: start afresh
    new_samples_ = 0;
  }
  if (window_.samples.empty()) window_.t0_camera_us = t0_camera_us;
  window_.samples.insert(window_.samples.end(), samples.begin(), samples.end());
  new_samples_ += samples.size();
  const auto kept = static_cast<std::size_t>(std::llround(options_.window_s * window_.sample_rate_hz));
  if (window_.samples.size() > kept) {
    const std::size_t drop = window_.samples.size() - kept;
    window_.samples.erase(window_.samples.begin(), window_.samples.begin() + static_cast<std::ptrdiff_t>(drop));
    window_.t0_camera_us += static_cast<double>(drop) * period_us;
  }
  if (static_cast<double>(new_samples_) >= options_.scan_every_s * window_.sample_rate_hz) scan();
}

void ToneStopScanner::scan() {
  new_samples_ = 0;
  if (options_.find_tone && !tone_found_) {
    const std::optional<FoundTone> tone = find_stopping_tone(window_, options_.tone_search);
    if (!tone) {
      // For the error message: a tone that stops outside the band searched (a buzzer other than
      // the one configured), until one is heard. The whole band costs as much as the scan
      // itself, so at every scan only in the first kOutsideEveryScanS of audio (the buzzer sounds
      // near the start, paper 1 II-G.1), then once per window's length.
      ++scans_without_tone_;
      const auto scans_per_window = static_cast<std::size_t>(std::max(1.0, options_.window_s / options_.scan_every_s));
      const bool early = static_cast<double>(scans_without_tone_) * options_.scan_every_s <= kOutsideEveryScanS;
      if (!heard_outside_hz_ && (early || scans_without_tone_ % scans_per_window == 0)) {
        ToneSearchOptions everywhere;
        everywhere.max_hz = std::min(everywhere.max_hz, window_.sample_rate_hz / 2.0);
        if (const std::optional<FoundTone> other = find_stopping_tone(window_, everywhere))
          heard_outside_hz_ = other->hz;
      }
      return;
    }
    options_.detector.tone_hz = tone->hz;
    tone_found_ = true;
  }
  BuzzerStop stop;
  try {
    stop = detect_buzzer_stop(window_, options_.detector);
  } catch (const Error&) {
    return;  // no tone stop in this window: the usual case
  }
  const double end_us =
      window_.t0_camera_us + 1e6 * static_cast<double>(window_.samples.size()) / window_.sample_rate_hz;
  if (stop.t_camera_us > end_us - 1e6 * options_.margin_s) return;  // wait for the silence after it
  if (!stops_.empty() && std::abs(stop.t_camera_us - stops_.back().t_camera_us) < 1e6 * options_.merge_s) return;
  stops_.push_back(stop);
}

}  // namespace posefuse::sync
