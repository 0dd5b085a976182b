#include "sim/sync_signals.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/error.hpp"
#include "sim/option_checks.hpp"
#include "sim/sim_rng.hpp"
#include "sync/broadcast_offsets.hpp"

namespace posefuse::sim {
namespace {

void check_devices(const std::vector<SimDevice>& devices) {
  if (devices.empty()) throw_invalid("devices", "no devices");
  for (std::size_t i = 0; i < devices.size(); ++i) {
    if (devices[i].device_id.empty()) throw_invalid("devices[" + std::to_string(i) + "].device_id", "empty");
    for (std::size_t j = 0; j < i; ++j) {
      if (devices[j].device_id == devices[i].device_id) {
        throw_invalid("devices[" + std::to_string(i) + "].device_id", "duplicate '" + devices[i].device_id + "'");
      }
    }
  }
}

std::int16_t to_s16(double x) {
  const double scaled = std::round(x * 32767.0);
  return static_cast<std::int16_t>(std::clamp(scaled, -32768.0, 32767.0));
}

}  // namespace

BleBroadcastResult ble_broadcast_receipts(const std::vector<SimDevice>& devices, const BleBroadcastOptions& options,
                                          std::uint64_t seed) {
  check_devices(devices);
  require_finite(options.first_broadcast_s, "ble.first_broadcast_s");
  require_positive(options.interval_s, "ble.interval_s");
  require_positive(options.clock_resolution_s, "ble.clock_resolution_s");
  if (!(options.receive_probability > 0 && options.receive_probability <= 1)) {
    throw_invalid("ble.receive_probability", "must be in (0, 1]");
  }
  if (options.rounds_received_by_all < 1) throw_invalid("ble.rounds_received_by_all", "must be >= 1");
  if (options.max_rounds < 1 || options.max_rounds > 100000) throw_invalid("ble.max_rounds", "must be in 1..100000");
  require_non_negative(options.receipt_jitter_s, "ble.receipt_jitter_s");

  require_non_negative(options.repeat_every_s, "ble.repeat_every_s");
  require_finite(options.repeat_until_s, "ble.repeat_until_s");
  if (options.repeat_every_s > 0 && options.repeat_every_s < options.interval_s) {
    throw_invalid("ble.repeat_every_s", "must be 0 (one burst) or at least ble.interval_s");
  }

  SimRng rng(seed, "ble_broadcast");
  BleBroadcastResult result;
  for (int burst = 0;; ++burst) {
    const double burst_start = options.first_broadcast_s + burst * options.repeat_every_s;
    if (burst > 0 && (options.repeat_every_s <= 0 || burst_start >= options.repeat_until_s)) break;
    const double next_burst =
        options.repeat_every_s > 0 ? burst_start + options.repeat_every_s : std::numeric_limits<double>::infinity();
    int complete_rounds = 0;
    for (int round = 0; round < options.max_rounds && complete_rounds < options.rounds_received_by_all; ++round) {
      const double t_camera = burst_start + round * options.interval_s;
      if (t_camera >= next_burst) break;
      const auto sequence = static_cast<std::uint32_t>(result.broadcast_t_camera_s.size());
      result.broadcast_t_camera_s.push_back(t_camera);
      bool all = true;
      for (const SimDevice& device : devices) {
        const bool received = rng.uniform() < options.receive_probability;
        const double jitter = options.receipt_jitter_s * rng.normal();
        if (!received) {
          all = false;
          continue;
        }
        const double device_s = 1e-6 * static_cast<double>(device.clock.to_device_us(t_camera + jitter));
        const double quantised_s = std::floor(device_s / options.clock_resolution_s) * options.clock_resolution_s;
        v1::SyncEvent event;
        event.set_t_us(std::llround(quantised_s * 1e6));
        event.set_device_id(device.device_id);
        event.set_kind(v1::SyncEvent::BLE_BROADCAST_RECEIPT);
        event.set_payload(sync::ble_sequence_payload(sequence));
        result.events.push_back(std::move(event));
      }
      if (all) ++complete_rounds;
    }
  }
  return result;
}

BuzzerResult buzzer_stop(const SimDevice& base, const BuzzerOptions& buzzer, const AudioOptions& audio,
                         std::uint64_t seed) {
  check_devices({base});
  require_positive(buzzer.duration_s, "buzzer.duration_s");
  require_positive(buzzer.amplitude, "buzzer.amplitude");
  require_positive(buzzer.speed_of_sound_m_s, "buzzer.speed_of_sound_m_s");
  require_non_negative(buzzer.distance_m, "buzzer.distance_m");
  if (audio.sample_rate_hz < 8000 || audio.sample_rate_hz > 384000) {
    throw_invalid("audio.sample_rate_hz", "must be in 8000..384000, got " + std::to_string(audio.sample_rate_hz));
  }
  const double rate = audio.sample_rate_hz;
  require_positive(buzzer.tone_hz, "buzzer.tone_hz");
  if (buzzer.tone_hz >= rate / 2) throw_invalid("buzzer.tone_hz", "must be below the Nyquist frequency");
  require_finite(audio.t_begin_s, "audio.t_begin_s");
  require_positive(audio.duration_s, "audio.duration_s");
  require_positive(audio.chunk_s, "audio.chunk_s");
  require_non_negative(audio.noise_rms, "audio.noise_rms");

  BuzzerResult result;
  result.stop_camera_s = base.clock.to_camera_s(buzzer.stop_device_us);
  result.stop_heard_camera_s = result.stop_camera_s + buzzer.distance_m / buzzer.speed_of_sound_m_s;
  const double heard_start_s = result.stop_heard_camera_s - buzzer.duration_s;
  const double audio_end_s = audio.t_begin_s + audio.duration_s;
  if (!(result.stop_heard_camera_s > audio.t_begin_s && result.stop_heard_camera_s < audio_end_s)) {
    throw_invalid("buzzer.stop_device_us", "the stop is heard at " + std::to_string(result.stop_heard_camera_s) +
                                               " s camera time, outside the audio span");
  }

  result.stop_event.set_t_us(buzzer.stop_device_us);
  result.stop_event.set_device_id(base.device_id);
  result.stop_event.set_kind(v1::SyncEvent::BUZZER_STOP);
  // Every stop as [tone starts, microphone hears the stop) on the camera clock.
  std::vector<std::pair<double, double>> tones = {{heard_start_s, result.stop_heard_camera_s}};
  std::int64_t previous_us = buzzer.stop_device_us;
  for (std::size_t k = 0; k < buzzer.later_stops_device_us.size(); ++k) {
    const std::int64_t stop_us = buzzer.later_stops_device_us[k];
    const std::string field = "buzzer.later_stops_device_us[" + std::to_string(k) + "]";
    if (1e-6 * static_cast<double>(stop_us - previous_us) < buzzer.duration_s + 1.0) {
      throw_invalid(field, "must be at least duration_s + 1 s after the previous stop (a second of silence)");
    }
    const double stop_camera_s = base.clock.to_camera_s(stop_us);
    const double heard_s = stop_camera_s + buzzer.distance_m / buzzer.speed_of_sound_m_s;
    if (!(heard_s > audio.t_begin_s && heard_s < audio_end_s)) {
      throw_invalid(field,
                    "the stop is heard at " + std::to_string(heard_s) + " s camera time, outside the audio span");
    }
    tones.emplace_back(heard_s - buzzer.duration_s, heard_s);
    result.later_stops_camera_s.push_back(stop_camera_s);
    v1::SyncEvent& event = result.later_stop_events.emplace_back(result.stop_event);
    event.set_t_us(stop_us);
    previous_us = stop_us;
  }

  const auto total = static_cast<std::size_t>(std::llround(audio.duration_s * rate));
  const auto per_chunk = std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(audio.chunk_s * rate)));
  SimRng rng(seed, "audio_noise");
  for (std::size_t first = 0; first < total; first += per_chunk) {
    const std::size_t end = std::min(total, first + per_chunk);
    std::string pcm;
    pcm.reserve(2 * (end - first));
    for (std::size_t i = first; i < end; ++i) {
      const double t = audio.t_begin_s + static_cast<double>(i) / rate;
      double x = audio.noise_rms * rng.normal();
      for (const auto& [start_s, stop_s] : tones) {
        if (t >= start_s && t < stop_s)
          x += buzzer.amplitude * std::sin(2.0 * EIGEN_PI * buzzer.tone_hz * (t - start_s));
      }
      const auto v = static_cast<std::uint16_t>(to_s16(x));
      pcm.push_back(static_cast<char>(v & 0xffu));
      pcm.push_back(static_cast<char>(v >> 8));
    }
    v1::AudioChunk chunk;
    chunk.set_t_us(std::llround((audio.t_begin_s + static_cast<double>(first) / rate) * 1e6));
    chunk.set_sample_rate_hz(audio.sample_rate_hz);
    chunk.set_channels(1);
    chunk.set_pcm_s16le(std::move(pcm));
    result.audio.push_back(std::move(chunk));
  }
  return result;
}

}  // namespace posefuse::sim
