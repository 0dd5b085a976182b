#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "common/error.hpp"
#include "sim/device_clock.hpp"
#include "sim/sync_signals.hpp"
#include "sync/broadcast_offsets.hpp"

using posefuse::Error;
using namespace posefuse::sim;

namespace {

std::vector<double> decode_pcm(const std::vector<posefuse::v1::AudioChunk>& chunks) {
  std::vector<double> x;
  for (const auto& c : chunks) {
    const std::string& pcm = c.pcm_s16le();
    for (std::size_t i = 0; i + 1 < pcm.size(); i += 2) {
      const auto v = static_cast<std::int16_t>(static_cast<std::uint16_t>(static_cast<unsigned char>(pcm[i])) |
                                               static_cast<std::uint16_t>(static_cast<unsigned char>(pcm[i + 1]) << 8));
      x.push_back(v / 32767.0);
    }
  }
  return x;
}

// A simple envelope detector: the rectified signal, held over one tone period, compared with
// half the tone amplitude; the stop is the end of the last sample above it.
double detect_stop_s(const std::vector<double>& x, double rate, double t_begin_s, double amplitude) {
  std::size_t last = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (std::abs(x[i]) > 0.5 * amplitude) last = i;
  }
  return t_begin_s + static_cast<double>(last + 1) / rate;
}

}  // namespace

TEST(DeviceClock, RoundTripAndDrift) {
  const DeviceClock clock{123.456789, 47e-6};
  for (std::int64_t device_us : {std::int64_t{0}, std::int64_t{123456789}, std::int64_t{130000001}, std::int64_t{-5},
                                 std::int64_t{987654321012}}) {
    EXPECT_EQ(clock.to_device_us(clock.to_camera_s(device_us)), device_us);
  }
  for (double t = -3.0; t < 4000.0; t += 97.3) {
    EXPECT_LE(std::abs(clock.to_camera_s(clock.to_device_us(t)) - t), 0.5e-6 + 1e-9);
  }
  // After 60 s of camera time the device clock has run 60 s * (1 + drift): 2.82 ms more.
  EXPECT_EQ(clock.to_device_us(60.0) - clock.to_device_us(0.0), 60'002'820);
  EXPECT_THROW(clock.to_device_us(std::nan("")), Error);
  EXPECT_THROW((DeviceClock{0.0, 0.5}.to_device_us(1.0)), Error);
}

TEST(DeviceClock, RegularTicksOnTheDeviceClock) {
  const DeviceClock clock{-2.5, -30e-6};
  const DeviceTicks ticks = regular_device_ticks(clock, 80.0, 10.0, 70.0);
  // 60 s of camera time is 60 * (1 - 30e-6) s of device time: 4799.86 periods.
  EXPECT_GE(ticks.t_device_us.size(), 4799u);
  EXPECT_LE(ticks.t_device_us.size(), 4800u);
  for (std::size_t k = 0; k < ticks.t_device_us.size(); ++k) {
    EXPECT_EQ(ticks.t_device_us[k] % 12500, 0);
    if (k > 0) {
      EXPECT_EQ(ticks.t_device_us[k] - ticks.t_device_us[k - 1], 12500);
    }
    EXPECT_GE(ticks.t_camera_s[k], 10.0);
    EXPECT_LE(ticks.t_camera_s[k], 70.0);
    EXPECT_NEAR(clock.to_camera_s(ticks.t_device_us[k]), ticks.t_camera_s[k], 1e-9);
  }
  std::vector<posefuse::imu::ImuSample> samples(ticks.t_device_us.size());
  stamp_on_device_clock(samples, ticks.t_device_us);
  EXPECT_EQ(samples.back().t_us, ticks.t_device_us.back());
  samples.pop_back();
  EXPECT_THROW(stamp_on_device_clock(samples, ticks.t_device_us), Error);
}

TEST(PacketLoss, RateAndBurstLengthNearConfigured) {
  PacketLossModel model;
  model.loss_rate = 0.05;
  model.mean_burst_packets = 4.0;
  const std::size_t n = 400000;
  const std::vector<bool> lost = lost_samples(model, n, 3);
  std::size_t lost_count = 0, bursts = 0;
  for (std::size_t k = 0; k < n; ++k) {
    lost_count += lost[k] ? 1 : 0;
    if (lost[k] && (k == 0 || !lost[k - 1])) ++bursts;
  }
  const double rate = static_cast<double>(lost_count) / static_cast<double>(n);
  const double burst = static_cast<double>(lost_count) / static_cast<double>(bursts);
  // ~5000 bursts: the estimates' relative standard deviations are about 2-3 %.
  EXPECT_NEAR(rate, 0.05, 0.05 * 0.1);
  EXPECT_NEAR(burst, 4.0, 4.0 * 0.1);
}

TEST(PacketLoss, WholePacketsAndSeeds) {
  PacketLossModel model;
  model.loss_rate = 0.1;
  model.samples_per_packet = 4;
  const std::vector<bool> a = lost_samples(model, 10000, 11);
  for (std::size_t k = 0; k < a.size(); k += 4) {
    for (std::size_t j = 1; j < 4; ++j) EXPECT_EQ(a[k + j], a[k]);
  }
  EXPECT_EQ(lost_samples(model, 10000, 11), a);
  EXPECT_NE(lost_samples(model, 10000, 12), a);
  // No loss configured: nothing lost.
  model.loss_rate = 0;
  const auto none = lost_samples(model, 1000, 1);
  EXPECT_EQ(std::count(none.begin(), none.end(), true), 0);

  std::vector<posefuse::imu::ImuSample> samples(5);
  for (int k = 0; k < 5; ++k) samples[static_cast<std::size_t>(k)].t_us = k;
  const auto kept = drop_lost(samples, {false, true, true, false, false});
  ASSERT_EQ(kept.size(), 3u);
  EXPECT_EQ(kept[1].t_us, 3);
  EXPECT_THROW(drop_lost(samples, {false}), Error);
}

TEST(PacketLoss, RejectsBadModels) {
  PacketLossModel model;
  model.loss_rate = 1.0;
  EXPECT_THROW(lost_samples(model, 10, 1), Error);
  model.loss_rate = 0.6;
  model.mean_burst_packets = 1.0;  // independent losses: at most 50 % reachable
  EXPECT_THROW(lost_samples(model, 10, 1), Error);
  model = PacketLossModel();
  model.mean_burst_packets = 0.5;
  EXPECT_THROW(lost_samples(model, 10, 1), Error);
  model = PacketLossModel();
  model.samples_per_packet = 0;
  EXPECT_THROW(lost_samples(model, 10, 1), Error);
}

TEST(BleBroadcast, ReceiptsMapThroughEachClock) {
  const std::vector<SimDevice> devices = {{"base", {5.0, 20e-6}}, {"arm_right", {-17.25, -35e-6}}};
  BleBroadcastOptions options;
  const BleBroadcastResult r = ble_broadcast_receipts(devices, options, 5);
  ASSERT_FALSE(r.events.empty());
  std::map<std::uint32_t, std::map<std::string, std::int64_t>> by_round;
  std::map<std::string, std::int64_t> last_t;
  for (const auto& e : r.events) {
    EXPECT_EQ(e.kind(), posefuse::v1::SyncEvent::BLE_BROADCAST_RECEIPT);
    const std::uint32_t round = posefuse::sync::ble_sequence_from_payload(e.payload());
    by_round[round][e.device_id()] = e.t_us();
    if (last_t.count(e.device_id())) {
      EXPECT_GE(e.t_us(), last_t[e.device_id()]);
    }
    last_t[e.device_id()] = e.t_us();
    // The receipt, mapped back to the camera clock, is the broadcast within one BLE tick.
    const SimDevice& d = e.device_id() == "base" ? devices[0] : devices[1];
    const double back = d.clock.to_camera_s(e.t_us());
    const double truth = r.broadcast_t_camera_s[round];
    EXPECT_LE(back, truth + 1e-6);
    EXPECT_GE(back, truth - options.clock_resolution_s * 1.001 - 1e-6);
  }
  int complete = 0;
  for (const auto& [round, receipts] : by_round) complete += receipts.size() == 2 ? 1 : 0;
  EXPECT_EQ(complete, options.rounds_received_by_all);  // the PC stopped then
  EXPECT_EQ(posefuse::sync::ble_sequence_from_payload(posefuse::sync::ble_sequence_payload(0x01020304u)), 0x01020304u);
  EXPECT_THROW(posefuse::sync::ble_sequence_from_payload("abc"), Error);
}

TEST(BleBroadcast, RepeatedBurstsSpreadReceiptsOverTheSession) {
  const std::vector<SimDevice> devices = {{"base", {5.0, 20e-6}}, {"arm_right", {-17.25, -35e-6}}};
  BleBroadcastOptions once;
  const BleBroadcastResult first = ble_broadcast_receipts(devices, once, 5);
  BleBroadcastOptions options;
  options.repeat_every_s = 10.0;
  options.repeat_until_s = 60.0;
  const BleBroadcastResult r = ble_broadcast_receipts(devices, options, 5);
  // The first burst is the paper's single burst, unchanged.
  ASSERT_GT(r.events.size(), first.events.size());
  for (std::size_t k = 0; k < first.events.size(); ++k) {
    EXPECT_EQ(r.events[k].SerializeAsString(), first.events[k].SerializeAsString());
  }
  // Bursts start at 0.5, 10.5, ..., 50.5 s; each ends with rounds_received_by_all complete rounds;
  // sequence numbers index broadcast_t_camera_s and count on across bursts.
  std::map<int, int> complete_by_burst;
  std::map<std::uint32_t, int> receipts_by_round;
  for (const auto& e : r.events) ++receipts_by_round[posefuse::sync::ble_sequence_from_payload(e.payload())];
  for (const auto& [round, receipts] : receipts_by_round) {
    ASSERT_LT(round, r.broadcast_t_camera_s.size());
    const int burst = static_cast<int>(std::floor((r.broadcast_t_camera_s[round] - 0.5) / 10.0 + 1e-9));
    complete_by_burst[burst] += receipts == 2 ? 1 : 0;
  }
  ASSERT_EQ(complete_by_burst.size(), 6u);
  for (const auto& [burst, complete] : complete_by_burst) EXPECT_EQ(complete, options.rounds_received_by_all) << burst;
  EXPECT_NEAR(r.broadcast_t_camera_s.back(), 50.5, 2.0);
  options.repeat_every_s = 0.05;  // shorter than the broadcast interval
  EXPECT_THROW(ble_broadcast_receipts(devices, options, 1), Error);
  options.repeat_every_s = -1.0;
  EXPECT_THROW(ble_broadcast_receipts(devices, options, 1), Error);
}

TEST(BleBroadcast, SeedsAndBadOptions) {
  const std::vector<SimDevice> devices = {{"base", {}}, {"arm", {1.0, 0.0}}};
  BleBroadcastOptions options;
  options.receipt_jitter_s = 50e-6;
  const auto a = ble_broadcast_receipts(devices, options, 1);
  const auto b = ble_broadcast_receipts(devices, options, 1);
  const auto c = ble_broadcast_receipts(devices, options, 2);
  ASSERT_EQ(a.events.size(), b.events.size());
  for (std::size_t k = 0; k < a.events.size(); ++k)
    EXPECT_EQ(a.events[k].SerializeAsString(), b.events[k].SerializeAsString());
  bool same = a.events.size() == c.events.size();
  for (std::size_t k = 0; same && k < a.events.size(); ++k)
    same = a.events[k].SerializeAsString() == c.events[k].SerializeAsString();
  EXPECT_FALSE(same);
  options.receive_probability = 0;
  EXPECT_THROW(ble_broadcast_receipts(devices, options, 1), Error);
  options = BleBroadcastOptions();
  EXPECT_THROW(ble_broadcast_receipts({{"x", {}}, {"x", {}}}, options, 1), Error);
}

TEST(Buzzer, LaterStopsEachWithTheirToneAndEvent) {
  const SimDevice base{"base", {5.0, 20e-6}};
  BuzzerOptions buzzer;
  buzzer.stop_device_us = base.clock.to_device_us(1.5);
  buzzer.later_stops_device_us = {base.clock.to_device_us(4.0), base.clock.to_device_us(7.25)};
  AudioOptions audio;
  audio.duration_s = 8.0;
  const BuzzerResult r = buzzer_stop(base, buzzer, audio, 2);
  ASSERT_EQ(r.later_stop_events.size(), 2u);
  ASSERT_EQ(r.later_stops_camera_s.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(r.later_stop_events[k].t_us(), buzzer.later_stops_device_us[k]);
    EXPECT_EQ(r.later_stop_events[k].kind(), posefuse::v1::SyncEvent::BUZZER_STOP);
    EXPECT_NEAR(r.later_stops_camera_s[k], k == 0 ? 4.0 : 7.25, 1e-6);
  }
  // Each stop is heard where the simple detector finds the last stop of the audio up to it.
  const std::vector<double> x = decode_pcm(r.audio);
  const double rate = audio.sample_rate_hz;
  for (const double stop : {1.5, 4.0, 7.25}) {
    const auto n = static_cast<std::size_t>((stop + 0.5) * rate);
    const std::vector<double> upto(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(n));
    EXPECT_NEAR(detect_stop_s(upto, rate, 0.0, buzzer.amplitude), stop + buzzer.distance_m / buzzer.speed_of_sound_m_s,
                1.0 / buzzer.tone_hz + 1.0 / rate);
  }
  buzzer.later_stops_device_us = {base.clock.to_device_us(2.8)};  // less than a second of silence
  EXPECT_THROW(buzzer_stop(base, buzzer, audio, 2), Error);
  buzzer.later_stops_device_us = {base.clock.to_device_us(9.0)};  // after the audio
  EXPECT_THROW(buzzer_stop(base, buzzer, audio, 2), Error);
}

// The stop heard in the audio, by a simple envelope detector, within a few sample periods; and
// with it the base clock's offset, as paper 1 II-G1 uses it.
TEST(Buzzer, StopRecoveredFromAudio) {
  for (std::uint32_t rate : {16000u, 48000u}) {
    const SimDevice base{"base", {3.2, 40e-6}};
    BuzzerOptions buzzer;
    buzzer.stop_device_us = 5'123'457;
    AudioOptions audio;
    audio.sample_rate_hz = rate;
    audio.t_begin_s = 0.5;
    audio.duration_s = 2.0;
    const BuzzerResult r = buzzer_stop(base, buzzer, audio, 9);
    EXPECT_EQ(r.stop_event.kind(), posefuse::v1::SyncEvent::BUZZER_STOP);
    EXPECT_EQ(r.stop_event.device_id(), "base");
    EXPECT_EQ(r.stop_event.t_us(), buzzer.stop_device_us);
    EXPECT_NEAR(r.stop_camera_s, base.clock.to_camera_s(buzzer.stop_device_us), 1e-12);
    EXPECT_NEAR(r.stop_heard_camera_s - r.stop_camera_s, 0.05 / 343.0, 1e-12);

    const std::vector<double> x = decode_pcm(r.audio);
    ASSERT_EQ(x.size(), static_cast<std::size_t>(2.0 * rate));
    const double detected = detect_stop_s(x, rate, audio.t_begin_s, buzzer.amplitude);
    EXPECT_NEAR(detected, r.stop_heard_camera_s, 3.0 / rate) << rate << " Hz";
    std::printf("buzzer stop at %u Hz: detected - truth = %+.1f us (sample period %.1f us)\n", rate,
                1e6 * (detected - r.stop_heard_camera_s), 1e6 / rate);
    // Offset of the base clock recovered from the detected stop (drift known).
    const double offset = 1e-6 * static_cast<double>(r.stop_event.t_us()) -
                          (1.0 + base.clock.drift) * (detected - buzzer.distance_m / buzzer.speed_of_sound_m_s);
    EXPECT_NEAR(offset, base.clock.offset_s, 3.0 / rate);

    // Chunks: increasing, contiguous, as the header will say.
    for (std::size_t k = 0; k < r.audio.size(); ++k) {
      EXPECT_EQ(r.audio[k].sample_rate_hz(), rate);
      EXPECT_EQ(r.audio[k].channels(), 1u);
      if (k > 0) {
        EXPECT_NEAR(static_cast<double>(r.audio[k].t_us() - r.audio[k - 1].t_us()), 1e5, 1.0);
      }
    }
  }
}

TEST(Buzzer, SeedsAndBadOptions) {
  const SimDevice base{"base", {}};
  const BuzzerResult a = buzzer_stop(base, BuzzerOptions(), AudioOptions(), 1);
  const BuzzerResult b = buzzer_stop(base, BuzzerOptions(), AudioOptions(), 1);
  const BuzzerResult c = buzzer_stop(base, BuzzerOptions(), AudioOptions(), 2);
  EXPECT_EQ(a.audio[3].pcm_s16le(), b.audio[3].pcm_s16le());
  EXPECT_NE(a.audio[3].pcm_s16le(), c.audio[3].pcm_s16le());
  AudioOptions audio;
  audio.sample_rate_hz = 4000;
  EXPECT_THROW(buzzer_stop(base, BuzzerOptions(), audio, 1), Error);
  audio = AudioOptions();
  audio.t_begin_s = 10.0;  // the stop (2 s) is not in the recording
  EXPECT_THROW(buzzer_stop(base, BuzzerOptions(), audio, 1), Error);
  BuzzerOptions buzzer;
  buzzer.tone_hz = 9000;  // above 8 kHz Nyquist
  EXPECT_THROW(buzzer_stop(base, buzzer, AudioOptions(), 1), Error);
}
