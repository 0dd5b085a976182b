#pragma once
// The session's device clocks mapped onto the camera clock from the stream itself (paper 1,
// II-G): the camera audio and the base IMU's BUZZER_STOP event give base -> camera (sound-based
// sync), BLE_BROADCAST_RECEIPT events give every other IMU -> base (broadcast-based sync).
//
// Scans the audio (mono: the first channel) for tone stops as it streams in
// (sync/tone_stop_scanner.hpp, bounded memory) and collects the sync events; try_build() returns
// the map once the base's first BUZZER_STOP is paired with a heard stop and every listed device
// shares at least one broadcast with the base. BLE payload: the broadcast's sequence number,
// 4 bytes uint32 little-endian (docs/simulator.md).
//
// Beyond paper 1: the buzzer may stop again later. The base's stop events (in the order of its
// clock) are paired with the heard stops: the first event with the heard stop that lets the
// most later events find a heard stop where it predicts them (0.5 s + 300 ppm of the time
// between), ties to the earliest; so a stop event that reaches the stream after several stops
// were heard (the base's clock can run far ahead of the camera's) is still paired right. All
// pairs join the base -> camera fit, which then has a drift; later BLE receipts join each IMU's
// fit. try_build() again after more of them came in gives the refined map.
#include <optional>
#include <string>
#include <vector>

#include "session/session_inputs.hpp"
#include "sync/broadcast_offsets.hpp"
#include "sync/clock_map.hpp"
#include "sync/linear_clock.hpp"
#include "sync/tone_stop_scanner.hpp"

namespace posefuse::session {

class StreamClocks {
 public:
  // buzzer_tone_hz: the buzzer's nominal frequency (the tone is measured within 10 % of it), or
  // nullopt to find it anywhere in 500-8000 Hz (sync/tone_search.hpp). Throws posefuse::Error
  // kInvalidArgument "buzzer_tone_hz" when it is not below the audio's Nyquist frequency.
  StreamClocks(std::string base_device, double audio_sample_rate_hz, unsigned audio_channels,
               std::optional<double> buzzer_tone_hz = sync::BuzzerStopOptions().tone_hz);

  // The camera microphone's audio (buzzer stops) and the clock events (the base's buzzer stops,
  // BLE receipts).
  void add(const AudioBlock& audio);
  void add(const ClockEvent& event);

  // The map base and `devices` -> camera, or nullopt while something is missing (why_not()
  // says what).
  std::optional<sync::ClockMap> try_build(const std::vector<std::string>& devices);
  // What is missing, as a warning would say it: field and message.
  struct Missing {
    std::string field;
    std::string message;
  };
  Missing why_not(const std::vector<std::string>& devices) const;

  const std::optional<sync::BuzzerStop>& buzzer() const { return buzzer_; }
  // The buzzer tone measured in the audio (nullopt before it is found, and without audio).
  std::optional<double> buzzer_tone_hz() const;
  // Sync inputs so far (BLE receipts, later buzzer stops and tone stops heard): when it grows,
  // a later try_build() refits offsets and drifts over everything.
  std::size_t sync_input_count() const { return receipts_.size() + base_stops_us_.size() + heard_stops().size(); }
  std::size_t receipt_count() const { return receipts_.size(); }
  // Buzzer stops after the first paired with a heard stop in the last try_build().
  std::size_t later_stops_used() const { return later_stops_used_; }

 private:
  const std::vector<sync::BuzzerStop>& heard_stops() const;  // tone stops found in the audio so far
  // The base's stop events paired with heard stops, the first event with heard stop first_heard.
  std::vector<sync::ClockObservation> paired_stops(std::size_t first_heard) const;

  std::string base_;
  unsigned channels_ = 0;
  bool auto_tone_ = false;             // forearm.buzzer_hz = auto
  double nominal_tone_hz_ = 0.0;       // else the frequency given
  sync::ToneSearchOptions tone_band_;  // where the tone is searched
  bool audio_seen_ = false;
  std::vector<std::int64_t> base_stops_us_;  // BUZZER_STOP events of the base, base clock, sorted
  std::optional<sync::BuzzerStop> buzzer_;   // the heard stop paired with the first event
  std::vector<sync::BroadcastReceipt> receipts_;
  std::optional<sync::ToneStopScanner> tone_stops_;  // none without an audio rate
  std::size_t later_stops_used_ = 0;
};

}  // namespace posefuse::session
