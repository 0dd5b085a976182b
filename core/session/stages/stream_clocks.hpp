#pragma once
// The session's device clocks mapped onto the camera clock from the stream itself (paper 1,
// II-G): the camera audio and the base IMU's BUZZER_STOP event give base -> camera (sound-based
// sync), BLE_BROADCAST_RECEIPT events give every other IMU -> base (broadcast-based sync).
//
// Collects audio (mono: the first channel; at most max_audio_s seconds from the first chunk, a
// stop is expected near the start) and sync events as they stream in; try_build() returns the
// map once the buzzer stop is found in the audio and every listed device shares at least one
// broadcast with the base. BLE payload: the broadcast's sequence number, 4 bytes uint32
// little-endian (docs/simulator.md).
#include <optional>
#include <string>
#include <vector>

#include "posefuse/v1/session.pb.h"
#include "sync/broadcast_offsets.hpp"
#include "sync/clock_map.hpp"
#include "sync/linear_clock.hpp"

namespace posefuse::session {

class StreamClocks {
 public:
  StreamClocks(std::string base_device, double audio_sample_rate_hz, unsigned audio_channels,
               double max_audio_s = 60.0);

  // Audio chunks and sync events; other chunks are ignored. Throws posefuse::Error
  // kInvalidArgument for a broadcast payload that is not 4 bytes.
  void add(const v1::SessionChunk& chunk);

  // The map base and `devices` -> camera, or nullopt while something is missing (why_not()
  // says what). Runs the buzzer detector at most once per second of new audio.
  std::optional<sync::ClockMap> try_build(const std::vector<std::string>& devices);
  // What is missing, as a warning would say it: field and message.
  struct Missing {
    std::string field;
    std::string message;
  };
  Missing why_not(const std::vector<std::string>& devices) const;

  const std::optional<sync::BuzzerStop>& buzzer() const { return buzzer_; }
  // BLE receipts collected so far: a later try_build() with more of them refits every IMU's
  // offset and drift against the base over all of them.
  std::size_t receipt_count() const { return receipts_.size(); }

 private:
  std::string base_;
  sync::AudioPcm audio_;
  unsigned channels_ = 0;
  double max_audio_s_ = 0.0;
  std::size_t samples_at_last_attempt_ = 0;
  std::optional<std::int64_t> base_stop_us_;
  std::string buzzer_error_;
  std::optional<sync::BuzzerStop> buzzer_;
  std::vector<sync::BroadcastReceipt> receipts_;
};

}  // namespace posefuse::session
