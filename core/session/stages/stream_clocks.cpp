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
}  // namespace

StreamClocks::StreamClocks(std::string base_device, double audio_sample_rate_hz, unsigned audio_channels)
    : base_(std::move(base_device)), channels_(audio_channels) {
  // A header without a usable audio rate has no audio to scan.
  if (std::isfinite(audio_sample_rate_hz) && audio_sample_rate_hz > 0.0) tone_stops_.emplace(audio_sample_rate_hz);
}

const std::vector<sync::BuzzerStop>& StreamClocks::heard_stops() const {
  static const std::vector<sync::BuzzerStop> none;
  return tone_stops_ ? tone_stops_->stops() : none;
}

void StreamClocks::add(const v1::SessionChunk& chunk) {
  if (chunk.has_audio() && channels_ > 0 && tone_stops_) {
    const v1::AudioChunk& a = chunk.audio();
    const std::size_t frames = a.pcm_s16le().size() / (2u * channels_);
    std::vector<std::int16_t> mono(frames);
    for (std::size_t i = 0; i < frames; ++i) std::memcpy(&mono[i], a.pcm_s16le().data() + 2 * channels_ * i, 2);
    tone_stops_->add(static_cast<double>(a.t_us()), mono);
    audio_seen_ = true;
  }
  if (!chunk.has_sync_event()) return;
  const v1::SyncEvent& e = chunk.sync_event();
  if (e.kind() == v1::SyncEvent::BUZZER_STOP && e.device_id() == base_) {
    base_stops_us_.insert(std::upper_bound(base_stops_us_.begin(), base_stops_us_.end(), e.t_us()), e.t_us());
  } else if (e.kind() == v1::SyncEvent::BLE_BROADCAST_RECEIPT) {
    if (e.payload().size() != 4) {
      throw_invalid("sync_event.payload", "a BLE receipt carries a 4-byte sequence number, got " +
                                              std::to_string(e.payload().size()) + " bytes");
    }
    std::uint32_t sequence = 0;
    for (int i = 3; i >= 0; --i) sequence = (sequence << 8) | static_cast<unsigned char>(e.payload()[static_cast<std::size_t>(i)]);
    receipts_.push_back({static_cast<std::int64_t>(sequence), e.device_id(), static_cast<double>(e.t_us())});
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
    const double tolerance_us =
        kPairToleranceUs + kPairDriftBound * static_cast<double>(base_stops_us_[e] - first_us);
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
    return {"sync_event", "no BUZZER_STOP event from the base IMU '" + base_ + "': its clock cannot be mapped "
                          "onto the camera's (paper 1, II-G.1)"};
  }
  if (!audio_seen_) return {"audio", "no camera audio: the buzzer stop cannot be heard"};
  if (heard_stops().empty()) {
    return {"audio", "the buzzer stop was not found in the audio (a " +
                         std::to_string(static_cast<int>(sync::BuzzerStopOptions().tone_hz)) +
                         " Hz tone that stops and stays silent for 0.7 s)"};
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
