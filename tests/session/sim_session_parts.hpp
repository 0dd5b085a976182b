#pragma once
// Pieces shared by the simulated sessions that drive the forearm stage
// (tests/session/forearm_session.cpp, bench/table1/table1_session.cpp): IMU batches and sync
// chunks keyed by camera time, the header's strap cameras and IMU devices, the end marker.
#include <algorithm>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "forearm/strap_detection.hpp"
#include "posefuse/v1/session.pb.h"
#include "session/session_inputs.hpp"
#include "session/stages/proto_values.hpp"
#include "sim/imu_device.hpp"
#include "sim/sync_signals.hpp"

namespace posefuse::session::testing {

// A chunk and the camera time it is sorted by.
struct TimedChunk {
  double key_s;
  v1::SessionChunk chunk;
};

struct SimChunkCounts {
  std::map<std::string, std::uint64_t> imu_samples;
  std::uint64_t audio_chunks = 0, audio_frames = 0, sync_events = 0;
};

// Every batch of a simulated device, keyed by its last sample's camera time.
inline void add_imu_chunks(const sim::ImuDeviceResult& imu, const sim::DeviceClock& clock,
                           std::vector<TimedChunk>& timed, SimChunkCounts& counts) {
  for (const v1::ImuBatch& batch : imu.batches) {
    counts.imu_samples[batch.device_id()] += static_cast<std::uint64_t>(batch.t_us_size());
    v1::SessionChunk chunk;
    *chunk.mutable_imu() = batch;
    timed.push_back({clock.to_camera_s(batch.t_us(batch.t_us_size() - 1)), std::move(chunk)});
  }
}

// Paper 1, II-G: the base IMU's buzzer stops at stop_camera_s in 2.5 s of camera audio (the
// BUZZER_STOP event only when `buzzer_event`), and BLE broadcasts from 0.5 s received by both
// (`ble`: one burst by default, paper 1), the buzzer sounding at tone_hz. Returns the audio sample
// rate.
inline std::uint32_t add_sync_chunks(const sim::SimDevice& base, const sim::SimDevice& arm, double stop_camera_s,
                                     bool buzzer_event, std::uint64_t seed, std::vector<TimedChunk>& timed,
                                     SimChunkCounts& counts, const sim::BleBroadcastOptions& ble = {},
                                     double tone_hz = sim::BuzzerOptions().tone_hz) {
  sim::BuzzerOptions buzzer;
  buzzer.stop_device_us = base.clock.to_device_us(stop_camera_s);
  buzzer.tone_hz = tone_hz;
  sim::AudioOptions audio;
  audio.duration_s = 2.5;
  const sim::BuzzerResult sound = sim::buzzer_stop(base, buzzer, audio, seed);
  for (const v1::AudioChunk& a : sound.audio) {
    counts.audio_frames += a.pcm_s16le().size() / 2;
    ++counts.audio_chunks;
    v1::SessionChunk chunk;
    *chunk.mutable_audio() = a;
    timed.push_back({static_cast<double>(a.t_us()) * 1e-6, std::move(chunk)});
  }
  if (buzzer_event) {
    v1::SessionChunk chunk;
    *chunk.mutable_sync_event() = sound.stop_event;
    timed.push_back({stop_camera_s, std::move(chunk)});
    ++counts.sync_events;
  }
  const sim::BleBroadcastResult receipts = sim::ble_broadcast_receipts({base, arm}, ble, seed + 1);
  for (const v1::SyncEvent& e : receipts.events) {
    const sim::DeviceClock& clock = e.device_id() == base.device_id ? base.clock : arm.clock;
    v1::SessionChunk chunk;
    *chunk.mutable_sync_event() = e;
    timed.push_back({clock.to_camera_s(e.t_us()), std::move(chunk)});
    ++counts.sync_events;
  }
  return audio.sample_rate_hz;
}

// Header fields for a right-arm IMU, a base IMU at 80 Hz, the strap cameras at 30 Hz and mono
// audio.
inline void set_forearm_header(const std::string& arm_id, const std::string& base_id,
                               const forearm::StrapCameras& cameras, std::uint32_t audio_rate_hz,
                               v1::SessionHeader& h) {
  for (const auto& [id, role] :
       {std::pair{arm_id, v1::ImuDevice::ARM_RIGHT}, std::pair{base_id, v1::ImuDevice::BASE}}) {
    v1::ImuDevice& d = *h.add_imu_devices();
    d.set_device_id(id);
    d.set_role(role);
    d.set_nominal_rate_hz(80.0);
  }
  *h.mutable_depth_intrinsics() = camera_intrinsics(cameras.depth);
  *h.mutable_color_intrinsics() = camera_intrinsics(cameras.color);
  *h.mutable_color_from_depth()->mutable_rotation() = to_proto(cameras.color_from_depth);
  *h.mutable_color_from_depth()->mutable_translation_m() = to_proto(cameras.color_from_depth_m);
  h.set_depth_rate_hz(30.0);
  h.set_color_rate_hz(30.0);
  h.set_audio_sample_rate_hz(audio_rate_hz);
  h.set_audio_channels(1);
}

// Header, the timed chunks sorted by camera time, and the end marker with `frames` depth,
// skeleton and colour frames.
inline std::vector<v1::SessionChunk> assemble_session(v1::SessionChunk header, std::vector<TimedChunk> timed,
                                                      std::uint64_t frames, const SimChunkCounts& counts) {
  std::stable_sort(timed.begin(), timed.end(),
                   [](const TimedChunk& a, const TimedChunk& b) { return a.key_s < b.key_s; });
  std::vector<v1::SessionChunk> chunks;
  chunks.reserve(timed.size() + 2);
  chunks.push_back(std::move(header));
  for (TimedChunk& t : timed) chunks.push_back(std::move(t.chunk));
  v1::SessionChunk end;
  v1::EndOfSession& e = *end.mutable_end();
  e.set_depth_frames(frames);
  e.set_skeleton_frames(frames);
  e.set_color_frames(frames);
  for (const auto& [id, n] : counts.imu_samples) (*e.mutable_imu_samples())[id] = n;
  e.set_audio_chunks(counts.audio_chunks);
  e.set_audio_frames(counts.audio_frames);
  e.set_sync_events(counts.sync_events);
  chunks.push_back(std::move(end));
  return chunks;
}

}  // namespace posefuse::session::testing
