// StreamClocks on the simulator's sync signals: the buzzer stop maps the base IMU onto the
// camera, BLE receipts map the arm IMU onto the base. Over a long session with a burst of
// broadcasts every 30 s (and the buzzer stopping again later), the map fitted from the first
// burst and stop alone drifts away from the truth; a later try_build() over everything holds it
// to a fraction of a millisecond.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "session/frame_assembler.hpp"
#include "session/stages/stream_clocks.hpp"
#include "sim/sync_signals.hpp"

namespace posefuse::session {
namespace {

constexpr double kSessionS = 600.0;

// What the frame assembler hands the stage's clocks for an audio or sync chunk (mono audio).
void add_chunk(StreamClocks& clocks, const v1::SessionChunk& chunk) {
  if (chunk.has_audio()) clocks.add(audio_block(chunk.audio(), 1));
  if (chunk.has_sync_event()) {
    if (const std::optional<ClockEvent> event = clock_event(chunk.sync_event())) clocks.add(*event);
  }
}

struct SyncStreams {
  sim::SimDevice base{"base", sim::DeviceClock{-1.7171, 12e-6}};
  sim::SimDevice arm{"arm", sim::DeviceClock{33.3333, -41e-6}};
  std::vector<v1::SessionChunk> audio_and_stop;
  std::vector<v1::SessionChunk> receipts;  // camera-time order
  std::vector<double> receipt_camera_s;
};

SyncStreams make_streams(double repeat_every_s) {
  SyncStreams s;
  sim::BuzzerOptions buzzer;
  buzzer.stop_device_us = s.base.clock.to_device_us(1.2);
  sim::AudioOptions audio;
  audio.duration_s = 2.5;
  const sim::BuzzerResult sound = sim::buzzer_stop(s.base, buzzer, audio, 3);
  for (const v1::AudioChunk& a : sound.audio) *s.audio_and_stop.emplace_back().mutable_audio() = a;
  *s.audio_and_stop.emplace_back().mutable_sync_event() = sound.stop_event;
  sim::BleBroadcastOptions ble;
  ble.repeat_every_s = repeat_every_s;
  ble.repeat_until_s = kSessionS;
  const sim::BleBroadcastResult r = sim::ble_broadcast_receipts({s.base, s.arm}, ble, 4);
  for (const v1::SyncEvent& e : r.events) {
    *s.receipts.emplace_back().mutable_sync_event() = e;
    const sim::DeviceClock& clock = e.device_id() == "base" ? s.base.clock : s.arm.clock;
    s.receipt_camera_s.push_back(clock.to_camera_s(e.t_us()));
  }
  return s;
}

// The arm's mapped time against the truth at camera time t.
double arm_error_us(const sync::ClockMap& map, const SyncStreams& s, double t_camera_s) {
  const double device_us = static_cast<double>(s.arm.clock.to_device_us(t_camera_s));
  return map.to_camera_us("arm", device_us) - 1e6 * s.arm.clock.to_camera_s(static_cast<std::int64_t>(device_us));
}

TEST(StreamClocks, LaterReceiptsRefitTheDriftOverTheSession) {
  const SyncStreams s = make_streams(30.0);
  StreamClocks clocks("base", 16000.0, 1);
  for (const auto& chunk : s.audio_and_stop) add_chunk(clocks, chunk);
  // The first burst only (the stage's first map, at calibration).
  std::size_t k = 0;
  for (; k < s.receipts.size() && s.receipt_camera_s[k] < 10.0; ++k) add_chunk(clocks, s.receipts[k]);
  const std::optional<sync::ClockMap> first = clocks.try_build({"arm"});
  ASSERT_TRUE(first.has_value()) << clocks.why_not({"arm"}).message;
  const std::size_t first_receipts = clocks.receipt_count();
  for (; k < s.receipts.size(); ++k) add_chunk(clocks, s.receipts[k]);
  EXPECT_GT(clocks.receipt_count(), 10 * first_receipts);  // 20 bursts
  const std::optional<sync::ClockMap> all = clocks.try_build({"arm"});
  ASSERT_TRUE(all.has_value());
  // The base's map rests on the single buzzer stop in both; the arm's error is the base's
  // error plus its own: compare the arm against the base to see what the receipts changed.
  const auto relative_error_us = [&](const sync::ClockMap& map, double t) {
    const double base_device_us = static_cast<double>(s.base.clock.to_device_us(t));
    const double base_error = map.to_camera_us("base", base_device_us) -
                              1e6 * s.base.clock.to_camera_s(static_cast<std::int64_t>(base_device_us));
    return arm_error_us(map, s, t) - base_error;
  };
  const double first_end_us = relative_error_us(*first, kSessionS);
  const double all_end_us = relative_error_us(*all, kSessionS);
  std::printf("arm vs base at %.0f s: first burst only %.0f us, all %zu receipts %.0f us (sigma %.0f us)\n", kSessionS,
              first_end_us, clocks.receipt_count(), all_end_us,
              all->sigma_us("arm", static_cast<double>(s.arm.clock.to_device_us(kSessionS))));
  // One burst spans about a second: its drift is mostly the prior, tens of ms off after 10 min.
  EXPECT_GT(std::abs(first_end_us), 5000.0);
  // Receipts over 600 s: stamps floored to the 312.5 us BLE tick on both clocks.
  for (double t = 0.0; t <= kSessionS; t += 60.0) EXPECT_LT(std::abs(relative_error_us(*all, t)), 300.0) << t;
}

// Five minutes with the buzzer stopping again every 100 s: the later stops, heard anywhere in
// the audio and paired by the first stop's prediction, give the base IMU's drift against the
// camera, which one stop leaves at the prior's zero.
TEST(StreamClocks, LaterBuzzerStopsGiveTheBaseDrift) {
  constexpr double kLongS = 300.0;
  const sim::SimDevice base{"base", sim::DeviceClock{-1.7171, 37e-6}};
  const sim::SimDevice arm{"arm", sim::DeviceClock{33.3333, -41e-6}};
  sim::BuzzerOptions buzzer;
  buzzer.stop_device_us = base.clock.to_device_us(1.2);
  for (const double t : {101.2, 201.2, 291.7}) buzzer.later_stops_device_us.push_back(base.clock.to_device_us(t));
  sim::AudioOptions audio;
  audio.duration_s = kLongS;
  audio.sample_rate_hz = 8000;  // the lowest rate the detector takes: five minutes scan quickly
  const sim::BuzzerResult sound = sim::buzzer_stop(base, buzzer, audio, 3);
  ASSERT_EQ(sound.later_stop_events.size(), 3u);
  sim::BleBroadcastOptions ble;
  ble.repeat_every_s = 30.0;
  ble.repeat_until_s = kLongS;
  const sim::BleBroadcastResult receipts = sim::ble_broadcast_receipts({base, arm}, ble, 4);

  StreamClocks clocks("base", audio.sample_rate_hz, 1);
  const auto add_event = [&](const v1::SyncEvent& e) {
    v1::SessionChunk chunk;
    *chunk.mutable_sync_event() = e;
    add_chunk(clocks, chunk);
  };
  // The stop events arrive before the audio (the stream orders events by the base's clock,
  // which may run far ahead of the camera's), the later ones first to check the reordering.
  for (const v1::SyncEvent& e : sound.later_stop_events) add_event(e);
  add_event(sound.stop_event);
  for (const v1::SyncEvent& e : receipts.events) add_event(e);
  std::optional<sync::ClockMap> first;
  for (const v1::AudioChunk& a : sound.audio) {
    v1::SessionChunk chunk;
    *chunk.mutable_audio() = a;
    add_chunk(clocks, chunk);
    if (!first && a.t_us() > 3'000'000) {
      first = clocks.try_build({"arm"});
      ASSERT_TRUE(first.has_value()) << clocks.why_not({"arm"}).message;
      EXPECT_EQ(clocks.later_stops_used(), 0u);
    }
  }
  const std::optional<sync::ClockMap> all = clocks.try_build({"arm"});
  ASSERT_TRUE(all.has_value());
  EXPECT_EQ(clocks.later_stops_used(), 3u);
  const auto error_us = [](const sync::ClockMap& map, const sim::SimDevice& d, double t) {
    const std::int64_t device_us = d.clock.to_device_us(t);
    return map.to_camera_us(d.device_id, static_cast<double>(device_us)) - 1e6 * d.clock.to_camera_s(device_us);
  };
  std::printf(
      "at %.0f s: base %.0f us (first stop only) -> %.0f us (4 stops, sigma %.0f us), arm %.0f -> %.0f us; "
      "base drift %.2f ppm (true %.2f)\n",
      kLongS, error_us(*first, base, kLongS), error_us(*all, base, kLongS),
      all->sigma_us("base", static_cast<double>(base.clock.to_device_us(kLongS))), error_us(*first, arm, kLongS),
      error_us(*all, arm, kLongS), all->camera_from("base").drift * 1e6, 1e6 * (1.0 / (1.0 + 37e-6) - 1.0));
  EXPECT_GT(std::abs(error_us(*first, base, kLongS)), 5000.0);  // 37 ppm over 300 s, unobserved
  // Four stops, each to about 0.1 ms (audio edge and the stamp's 0.2 ms): every mapped time
  // within a millisecond, the arm's through the base's.
  for (double t = 0.0; t <= kLongS; t += 30.0) {
    EXPECT_LT(std::abs(error_us(*all, base, t)), 1000.0) << t;
    EXPECT_LT(std::abs(error_us(*all, arm, t)), 1000.0) << t;
  }

  // The events after all the audio (a base clock far ahead of the camera's): four stops heard
  // before any event; the pairing still gives the first event the first stop.
  StreamClocks late("base", audio.sample_rate_hz, 1);
  for (const v1::AudioChunk& a : sound.audio) {
    v1::SessionChunk chunk;
    *chunk.mutable_audio() = a;
    add_chunk(late, chunk);
  }
  for (const v1::SyncEvent& e : receipts.events) {
    v1::SessionChunk chunk;
    *chunk.mutable_sync_event() = e;
    add_chunk(late, chunk);
  }
  v1::SessionChunk stop_chunk;
  *stop_chunk.mutable_sync_event() = sound.stop_event;
  add_chunk(late, stop_chunk);
  const std::optional<sync::ClockMap> one_event = late.try_build({"arm"});
  ASSERT_TRUE(one_event.has_value());
  EXPECT_LT(std::abs(error_us(*one_event, base, 1.2)), 1000.0);  // the first stop, not the last
  for (const v1::SyncEvent& e : sound.later_stop_events) {
    v1::SessionChunk chunk;
    *chunk.mutable_sync_event() = e;
    add_chunk(late, chunk);
  }
  const std::optional<sync::ClockMap> late_all = late.try_build({"arm"});
  ASSERT_TRUE(late_all.has_value());
  EXPECT_EQ(late.later_stops_used(), 3u);
  EXPECT_LT(std::abs(error_us(*late_all, base, kLongS)), 1000.0);
}

TEST(StreamClocks, ReceiptWithABadPayloadIsRejected) {
  StreamClocks clocks("base", 16000.0, 1);
  v1::SessionChunk chunk;
  v1::SyncEvent& e = *chunk.mutable_sync_event();
  e.set_kind(v1::SyncEvent::BLE_BROADCAST_RECEIPT);
  e.set_device_id("arm");
  e.set_payload("abc");
  try {
    add_chunk(clocks, chunk);  // the assembler refuses it: an item error, nothing reaches the clocks
    FAIL() << "expected an error";
  } catch (const Error& error) {
    EXPECT_EQ(error.field(), "sync_event.payload");
  }
  EXPECT_EQ(clocks.receipt_count(), 0u);
}

}  // namespace
}  // namespace posefuse::session
