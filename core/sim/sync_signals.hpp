#pragma once
// The signals paper 1 II-G synchronises clocks with, as session chunks.
//
// Sound: the base IMU stops its buzzer at a moment on its own clock (a BUZZER_STOP SyncEvent
// with that device timestamp); the camera microphone, a few cm away, hears the tone stop
// distance / speed_of_sound later on the camera clock (AudioChunk stream).
// BLE: the PC broadcasts advertisement packets; every IMU that receives one reports the receipt
// time on its own clock (BLE_BROADCAST_RECEIPT SyncEvents). Devices receiving the same packet
// receive it at the same moment (the paper's assumption; receipt_jitter_s relaxes it), and each
// timestamp is quantised to the BLE clock resolution, 0.3125 ms.
#include <cstdint>
#include <string>
#include <vector>

#include "posefuse/v1/session.pb.h"
#include "sim/device_clock.hpp"

namespace posefuse::sim {

struct SimDevice {
  std::string device_id;
  DeviceClock clock;
};

struct BleBroadcastOptions {
  double first_broadcast_s = 0.5;        // camera clock
  double interval_s = 0.1;               // between broadcasts, > 0
  double receive_probability = 0.6;      // per device and broadcast, (0, 1]
  int rounds_received_by_all = 3;        // the PC stops after this many broadcasts every device got
  int max_rounds = 200;                  // ... or after this many broadcasts
  double clock_resolution_s = 312.5e-6;  // BLE clock tick; timestamps are floored to it
  double receipt_jitter_s = 0.0;         // per device and receipt, standard deviation
  // Paper 1 broadcasts once, at the start. With repeat_every_s > 0 the PC starts another burst
  // (same stopping rule, sequence numbers counting on) every repeat_every_s after the first one
  // while the burst's start is before repeat_until_s: receipts spread over the session are what
  // makes the clocks' drift observable. A burst ends early where the next one begins.
  double repeat_every_s = 0.0;  // 0: one burst; otherwise >= interval_s
  double repeat_until_s = 0.0;  // camera clock
};

struct BleBroadcastResult {
  std::vector<v1::SyncEvent> events;         // in camera-time order
  std::vector<double> broadcast_t_camera_s;  // ground truth, one per broadcast sent (= sequence number)
};

BleBroadcastResult ble_broadcast_receipts(const std::vector<SimDevice>& devices, const BleBroadcastOptions& options,
                                          std::uint64_t seed);

struct BuzzerOptions {
  std::int64_t stop_device_us = 2'000'000;  // the stop command, on the base IMU's clock
  double duration_s = 1.0;                  // how long it buzzed before the stop
  double tone_hz = 2700.0;                  // a typical piezo buzzer
  double amplitude = 0.3;                   // of full scale, at the microphone
  double distance_m = 0.05;                 // buzzer to microphone
  double speed_of_sound_m_s = 343.0;
  // Paper 1 buzzes once. Later stops (base clock, increasing, each after its own duration_s of
  // tone and after at least a second of silence) make the base clock's drift against the camera
  // observable, e.g. one at the end of the session.
  std::vector<std::int64_t> later_stops_device_us;
};

struct AudioOptions {
  std::uint32_t sample_rate_hz = 16000;  // the Kinect v2 microphone array's rate; 48000 too
  double t_begin_s = 0.0;                // camera clock of the first sample frame
  double duration_s = 4.0;
  double noise_rms = 0.01;  // white noise, of full scale
  double chunk_s = 0.1;     // samples per AudioChunk = round(chunk_s * rate)
};

struct BuzzerResult {
  v1::SyncEvent stop_event;                      // BUZZER_STOP on the base clock
  std::vector<v1::AudioChunk> audio;             // mono PCM s16le on the camera clock
  double stop_camera_s = 0.0;                    // truth: the stop on the camera clock
  double stop_heard_camera_s = 0.0;              // truth: when the microphone hears it
  std::vector<v1::SyncEvent> later_stop_events;  // one per BuzzerOptions::later_stops_device_us
  std::vector<double> later_stops_camera_s;      // truth
};

// kInvalidArgument naming the field for bad options (rate outside 8 kHz..384 kHz, tone above
// Nyquist, heard stop outside the audio span, ...).
BuzzerResult buzzer_stop(const SimDevice& base, const BuzzerOptions& buzzer, const AudioOptions& audio,
                         std::uint64_t seed);

}  // namespace posefuse::sim
