#include "session/stages/stream_clocks.hpp"

#include <cmath>
#include <cstring>

#include "common/error.hpp"

namespace posefuse::session {

namespace {
// The base IMU's stamp of its own stop command and the buzzer's electro-acoustic delay.
constexpr double kBaseStopSigmaUs = 200.0;
}  // namespace

StreamClocks::StreamClocks(std::string base_device, double audio_sample_rate_hz, unsigned audio_channels,
                           double max_audio_s)
    : base_(std::move(base_device)), channels_(audio_channels), max_audio_s_(max_audio_s) {
  audio_.sample_rate_hz = audio_sample_rate_hz;
}

void StreamClocks::add(const v1::SessionChunk& chunk) {
  if (chunk.has_audio() && channels_ > 0 && !buzzer_) {
    const v1::AudioChunk& a = chunk.audio();
    const std::size_t frames = a.pcm_s16le().size() / (2u * channels_);
    if (audio_.samples.empty()) audio_.t0_camera_us = static_cast<double>(a.t_us());
    // Chunks are contiguous in a recording; a gap is filled with silence so times stay right.
    const double expected_us = audio_.t0_camera_us + 1e6 * static_cast<double>(audio_.samples.size()) / audio_.sample_rate_hz;
    const double gap_frames = std::round((static_cast<double>(a.t_us()) - expected_us) * 1e-6 * audio_.sample_rate_hz);
    const double limit = max_audio_s_ * audio_.sample_rate_hz;
    if (gap_frames > 0 && static_cast<double>(audio_.samples.size()) + gap_frames < limit) {
      audio_.samples.resize(audio_.samples.size() + static_cast<std::size_t>(gap_frames), 0);
    }
    for (std::size_t i = 0; i < frames && static_cast<double>(audio_.samples.size()) < limit; ++i) {
      std::int16_t value = 0;
      std::memcpy(&value, a.pcm_s16le().data() + 2 * channels_ * i, 2);
      audio_.samples.push_back(value);
    }
  }
  if (!chunk.has_sync_event()) return;
  const v1::SyncEvent& e = chunk.sync_event();
  if (e.kind() == v1::SyncEvent::BUZZER_STOP && e.device_id() == base_ && !base_stop_us_) {
    base_stop_us_ = e.t_us();
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

std::optional<sync::ClockMap> StreamClocks::try_build(const std::vector<std::string>& devices) {
  if (!buzzer_ && base_stop_us_ && audio_.samples.size() >= samples_at_last_attempt_ + static_cast<std::size_t>(audio_.sample_rate_hz)) {
    samples_at_last_attempt_ = audio_.samples.size();
    try {
      buzzer_ = sync::detect_buzzer_stop(audio_);
      buzzer_error_.clear();
    } catch (const Error& error) {
      buzzer_error_ = error.what();
    }
  }
  if (!buzzer_) return std::nullopt;
  sync::ClockMap clocks;
  const sync::ClockObservation stop =
      sync::buzzer_observation(*buzzer_, static_cast<double>(*base_stop_us_), kBaseStopSigmaUs);
  clocks.add_direct(base_, sync::fit_linear_clock({stop}).clock);
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
  if (!base_stop_us_) {
    return {"sync_event", "no BUZZER_STOP event from the base IMU '" + base_ + "': its clock cannot be mapped "
                          "onto the camera's (paper 1, II-G.1)"};
  }
  if (audio_.samples.empty()) return {"audio", "no camera audio: the buzzer stop cannot be heard"};
  if (!buzzer_) return {"audio", "the buzzer stop was not found in the audio: " + buzzer_error_};
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
