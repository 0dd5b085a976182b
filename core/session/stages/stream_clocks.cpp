#include "session/stages/stream_clocks.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "common/error.hpp"

namespace posefuse::session {

namespace {
// The base IMU's stamp of its own stop command and the buzzer's electro-acoustic delay.
constexpr double kBaseStopSigmaUs = 200.0;

// A later stop is paired with the heard stop nearest to where the first stop's map puts it,
// within this plus the drift prior's spread since the first stop.
constexpr double kPairToleranceUs = 500'000.0;
constexpr double kPairDriftBound = 300e-6;

// A buzzer's tone is searched this far (relative) either side of its nominal frequency: piezo
// buzzers are specified to a few percent.
constexpr double kToneTolerance = 0.1;
}  // namespace

StreamClocks::StreamClocks(std::string base_device, double audio_sample_rate_hz, unsigned audio_channels,
                           std::optional<double> buzzer_tone_hz)
    : base_(std::move(base_device)),
      channels_(audio_channels),
      auto_tone_(!buzzer_tone_hz),
      nominal_tone_hz_(buzzer_tone_hz.value_or(0.0)) {
  // A header without a usable audio rate has no audio to scan.
  if (!std::isfinite(audio_sample_rate_hz) || audio_sample_rate_hz <= 0.0) return;
  // The tone is always measured (sync/tone_stop_scanner.hpp, find_tone): within kToneTolerance
  // of the nominal frequency, or anywhere in 500-8000 Hz for auto.
  sync::ToneStopScannerOptions options;
  options.find_tone = true;
  const double nyquist_hz = audio_sample_rate_hz / 2.0;
  if (buzzer_tone_hz) {
    if (!(*buzzer_tone_hz > 0.0) || !(*buzzer_tone_hz < nyquist_hz)) {
      throw_invalid("buzzer_tone_hz", "is " + std::to_string(*buzzer_tone_hz) + " Hz; the audio's " +
                                          std::to_string(audio_sample_rate_hz) + " Hz rate needs a tone below " +
                                          std::to_string(nyquist_hz) + " Hz");
    }
    options.tone_search.min_hz = (1.0 - kToneTolerance) * *buzzer_tone_hz;
    options.tone_search.max_hz = std::min((1.0 + kToneTolerance) * *buzzer_tone_hz, nyquist_hz);
  } else {
    options.tone_search.max_hz = std::min(options.tone_search.max_hz, nyquist_hz);
  }
  tone_band_ = options.tone_search;
  tone_stops_.emplace(audio_sample_rate_hz, options);
}

std::optional<double> StreamClocks::buzzer_tone_hz() const {
  return tone_stops_ ? tone_stops_->tone_hz() : std::nullopt;
}

const std::vector<sync::BuzzerStop>& StreamClocks::heard_stops() const {
  static const std::vector<sync::BuzzerStop> none;
  return tone_stops_ ? tone_stops_->stops() : none;
}

void StreamClocks::add(const AudioBlock& audio) {
  if (channels_ == 0 || !tone_stops_) return;
  tone_stops_->add(static_cast<double>(audio.t_us), audio.mono);
  audio_seen_ = true;
}

void StreamClocks::add(const ClockEvent& event) {
  if (event.kind == ClockEvent::Kind::kBuzzerStop && event.device_id == base_) {
    base_stops_us_.insert(std::upper_bound(base_stops_us_.begin(), base_stops_us_.end(), event.t_us), event.t_us);
  } else if (event.kind == ClockEvent::Kind::kBleReceipt) {
    receipts_.push_back(
        {static_cast<std::int64_t>(event.ble_sequence), event.device_id, static_cast<double>(event.t_us)});
  }
}

std::vector<sync::ClockObservation> StreamClocks::paired_stops(std::size_t first_heard) const {
  const std::vector<sync::BuzzerStop>& heard = heard_stops();
  const std::int64_t first_us = base_stops_us_.front();
  const sync::ClockObservation first =
      sync::buzzer_observation(heard[first_heard], static_cast<double>(first_us), kBaseStopSigmaUs);
  const sync::LinearClock first_only = sync::fit_linear_clock({first}).clock;
  std::vector<sync::ClockObservation> stops = {first};
  std::vector<bool> used(heard.size(), false);
  used[first_heard] = true;
  for (std::size_t e = 1; e < base_stops_us_.size(); ++e) {
    const double predicted_us = first_only.to_reference_us(static_cast<double>(base_stops_us_[e]));
    const double tolerance_us = kPairToleranceUs + kPairDriftBound * static_cast<double>(base_stops_us_[e] - first_us);
    std::optional<std::size_t> best;
    for (std::size_t k = first_heard + 1; k < heard.size(); ++k) {
      const double distance = std::abs(heard[k].t_camera_us - predicted_us);
      if (!used[k] && distance <= tolerance_us &&
          (!best || distance < std::abs(heard[*best].t_camera_us - predicted_us))) {
        best = k;
      }
    }
    if (!best) continue;  // not heard (yet)
    used[*best] = true;
    stops.push_back(sync::buzzer_observation(heard[*best], static_cast<double>(base_stops_us_[e]), kBaseStopSigmaUs));
  }
  return stops;
}

std::optional<sync::ClockMap> StreamClocks::try_build(const std::vector<std::string>& devices) {
  if (base_stops_us_.empty() || heard_stops().empty()) return std::nullopt;
  // Which heard stop is the first event's: the one with which the most later events find their
  // own stop where it predicts them; ties go to the earliest (with one event: the first heard).
  std::vector<sync::ClockObservation> stops;
  for (std::size_t first_heard = 0; first_heard < heard_stops().size(); ++first_heard) {
    std::vector<sync::ClockObservation> candidate = paired_stops(first_heard);
    if (candidate.size() > stops.size()) {
      stops = std::move(candidate);
      buzzer_ = heard_stops()[first_heard];
    }
  }
  later_stops_used_ = stops.size() - 1;
  sync::ClockMap clocks;
  clocks.add_direct(base_, sync::fit_linear_clock(stops).clock);
  for (const std::string& device : devices) {
    if (device == base_) continue;
    std::vector<sync::ClockObservation> observations;
    try {
      observations = sync::broadcast_observations(receipts_, device, base_);
    } catch (const Error&) {
      return std::nullopt;  // no broadcast heard by both yet
    }
    clocks.add_via(device, base_, sync::fit_linear_clock(observations).clock);
  }
  return clocks;
}

StreamClocks::Missing StreamClocks::why_not(const std::vector<std::string>& devices) const {
  if (base_stops_us_.empty()) {
    return {"sync_event", "no BUZZER_STOP event from the base IMU '" + base_ +
                              "': its clock cannot be mapped "
                              "onto the camera's (paper 1, II-G.1)"};
  }
  if (!audio_seen_) return {"audio", "no camera audio: the buzzer stop cannot be heard"};
  if (heard_stops().empty()) {
    const auto hz = [](double f) { return std::to_string(static_cast<int>(std::lround(f))) + " Hz"; };
    if (!buzzer_tone_hz()) {
      const sync::ToneSearchOptions& band = tone_band_;
      std::string message =
          "no buzzer tone found in the audio: no tone between " + hz(band.min_hz) + " and " + hz(band.max_hz) +
          " sounds and stops (forearm.buzzer_hz = " + (auto_tone_ ? std::string("auto") : hz(nominal_tone_hz_)) + ")";
      if (const std::optional<double>& other = tone_stops_->heard_outside_hz()) {
        message += "; a tone that stops was heard at " + hz(*other) + ": set forearm.buzzer_hz to it or to 'auto'";
      }
      return {"audio", message};
    }
    return {"audio", "the buzzer stop was not found in the audio (a " + hz(*buzzer_tone_hz()) +
                         " tone, found there, that stops and stays silent for 0.7 s)"};
  }
  for (const std::string& device : devices) {
    if (device == base_) continue;
    try {
      sync::broadcast_observations(receipts_, device, base_);
    } catch (const Error&) {
      return {"sync_event", "no BLE broadcast heard by both '" + device + "' and the base IMU (paper 1, II-G.2)"};
    }
  }
  return {"", ""};
}

}  // namespace posefuse::session
