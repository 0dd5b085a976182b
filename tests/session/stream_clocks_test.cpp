// StreamClocks on the simulator's sync signals: the buzzer stop maps the base IMU onto the
// camera, BLE receipts map the arm IMU onto the base. Over a ten-minute session with a burst of
// broadcasts every 30 s, the map fitted from the first burst alone drifts away from the truth;
// a later try_build() over all receipts holds it to a fraction of a millisecond.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "session/stages/stream_clocks.hpp"
#include "sim/sync_signals.hpp"

namespace posefuse::session {
namespace {

constexpr double kSessionS = 600.0;

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
  for (const auto& chunk : s.audio_and_stop) clocks.add(chunk);
  // The first burst only (the stage's first map, at calibration).
  std::size_t k = 0;
  for (; k < s.receipts.size() && s.receipt_camera_s[k] < 10.0; ++k) clocks.add(s.receipts[k]);
  const std::optional<sync::ClockMap> first = clocks.try_build({"arm"});
  ASSERT_TRUE(first.has_value()) << clocks.why_not({"arm"}).message;
  const std::size_t first_receipts = clocks.receipt_count();
  for (; k < s.receipts.size(); ++k) clocks.add(s.receipts[k]);
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
  std::printf("arm vs base at %.0f s: first burst only %.0f us, all %zu receipts %.0f us (sigma %.0f us)\n",
              kSessionS, first_end_us, clocks.receipt_count(), all_end_us,
              all->sigma_us("arm", static_cast<double>(s.arm.clock.to_device_us(kSessionS))));
  // One burst spans about a second: its drift is mostly the prior, tens of ms off after 10 min.
  EXPECT_GT(std::abs(first_end_us), 5000.0);
  // Receipts over 600 s: stamps floored to the 312.5 us BLE tick on both clocks.
  for (double t = 0.0; t <= kSessionS; t += 60.0) EXPECT_LT(std::abs(relative_error_us(*all, t)), 300.0) << t;
}

TEST(StreamClocks, ReceiptWithABadPayloadIsRejected) {
  StreamClocks clocks("base", 16000.0, 1);
  v1::SessionChunk chunk;
  v1::SyncEvent& e = *chunk.mutable_sync_event();
  e.set_kind(v1::SyncEvent::BLE_BROADCAST_RECEIPT);
  e.set_device_id("arm");
  e.set_payload("abc");
  try {
    clocks.add(chunk);
    FAIL() << "expected an error";
  } catch (const Error& error) {
    EXPECT_EQ(error.field(), "sync_event.payload");
  }
  EXPECT_EQ(clocks.receipt_count(), 0u);
}

}  // namespace
}  // namespace posefuse::session
