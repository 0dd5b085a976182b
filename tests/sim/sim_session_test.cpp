// The simulator's IMU, audio and sync chunks together form a valid session stream.
#include <gtest/gtest.h>

#include <algorithm>

#include "session/session_validator.hpp"
#include "sim/imu_device.hpp"
#include "sim/scripted_motion.hpp"
#include "test_motion.hpp"

using namespace posefuse;
using namespace posefuse::sim;
using namespace posefuse::sim::testing;

namespace {

v1::SessionHeader make_header(const std::vector<std::pair<std::string, v1::ImuDevice::Role>>& devices) {
  v1::SessionHeader h;
  h.set_format_version(session::kFormatVersion);
  h.set_subject_id("sim");
  for (const auto& [id, role] : devices) {
    auto* d = h.add_imu_devices();
    d->set_device_id(id);
    d->set_role(role);
    d->set_nominal_rate_hz(80.0);
  }
  auto* k = h.mutable_depth_intrinsics();
  k->set_width(512);
  k->set_height(424);
  k->set_fx(365.0);
  k->set_fy(365.0);
  k->set_cx(256.0);
  k->set_cy(212.0);
  h.set_depth_rate_hz(30.0);
  h.set_audio_sample_rate_hz(16000);
  h.set_audio_channels(1);
  return h;
}

}  // namespace

TEST(SimSession, ImuAudioAndSyncChunksValidate) {
  const SimDevice base{"base", {3.0, 20e-6}};
  const SimDevice arm{"arm_right", {-1.5, -40e-6}};

  ForearmRollingOptions rolling;
  rolling.repetitions = 4;
  const ScriptedMotion motion = forearm_rolling(rolling);  // 10 s
  const SensorKinematics arm_motion(imu_trajectory(ArmGeometry(), motion));
  const Quat camera_mount = rot(0.2, Vec3::UnitZ());
  const SensorKinematics base_motion(
      sample_trajectory([](double) { return Vec3(2.5, 0, 0.8); }, [&](double) { return camera_mount; }, -0.1, 10.1));

  ImuDeviceOptions options;
  options.packet_loss.loss_rate = 0.02;
  options.synth.seed = 21;
  const ImuDeviceResult arm_imu = simulate_imu_device(arm_motion, arm, options, 0.0, 10.0);
  options.synth.seed = 22;
  const ImuDeviceResult base_imu = simulate_imu_device(base_motion, base, options, 0.0, 10.0);

  // Device timestamps tick every 12.5 ms on the device's own clock; truth maps through it.
  EXPECT_NEAR(static_cast<double>(arm_imu.ticks.t_device_us.size()), 800.0, 1.0);
  EXPECT_EQ(
      arm_imu.received.size() + static_cast<std::size_t>(std::count(arm_imu.lost.begin(), arm_imu.lost.end(), true)),
      arm_imu.ticks.t_device_us.size());
  EXPECT_LT(arm_imu.received.size(), arm_imu.ticks.t_device_us.size());  // some were lost
  for (const auto& s : arm_imu.received) {
    EXPECT_EQ(s.t_us % 12500, 0);
    const double t_camera = arm.clock.to_camera_s(s.t_us);
    EXPECT_GE(t_camera, 0.0);
    EXPECT_LE(t_camera, 10.0);
  }
  // Samples are the truth's, re-stamped: the first received sample is one of the truth's.
  const auto first = std::find(arm_imu.lost.begin(), arm_imu.lost.end(), false) - arm_imu.lost.begin();
  EXPECT_EQ(arm_imu.received.front().gyr_rad_s, arm_imu.truth.samples[static_cast<std::size_t>(first)].gyr_rad_s);

  const BleBroadcastResult ble = ble_broadcast_receipts({base, arm}, BleBroadcastOptions(), 23);
  BuzzerOptions buzzer;
  buzzer.stop_device_us = base.clock.to_device_us(2.0);
  AudioOptions audio;
  audio.duration_s = 10.0;
  const BuzzerResult sound = buzzer_stop(base, buzzer, audio, 24);

  std::vector<v1::SessionChunk> chunks;
  chunks.emplace_back().mutable_header()->CopyFrom(
      make_header({{"base", v1::ImuDevice::BASE}, {"arm_right", v1::ImuDevice::ARM_RIGHT}}));
  for (const auto& b : base_imu.batches) chunks.emplace_back().mutable_imu()->CopyFrom(b);
  for (const auto& b : arm_imu.batches) chunks.emplace_back().mutable_imu()->CopyFrom(b);
  for (const auto& a : sound.audio) chunks.emplace_back().mutable_audio()->CopyFrom(a);
  // Sync events in camera-time order, so that each device's stay non-decreasing.
  std::vector<std::pair<double, v1::SyncEvent>> sync;
  sync.emplace_back(base.clock.to_camera_s(sound.stop_event.t_us()), sound.stop_event);
  for (const auto& e : ble.events) {
    sync.emplace_back((e.device_id() == "base" ? base : arm).clock.to_camera_s(e.t_us()), e);
  }
  std::stable_sort(sync.begin(), sync.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& [t, e] : sync) chunks.emplace_back().mutable_sync_event()->CopyFrom(e);

  session::SessionValidator validator;
  for (const auto& c : chunks) ASSERT_NO_THROW(validator.check(c)) << c.ShortDebugString().substr(0, 200);
  v1::SessionChunk end;
  end.mutable_end()->CopyFrom(validator.counts());
  ASSERT_NO_THROW(validator.check(end));
  EXPECT_NO_THROW(validator.finish());
  EXPECT_EQ(validator.counts().imu_samples().at("arm_right"), arm_imu.received.size());
  EXPECT_EQ(validator.counts().audio_frames(), 160000u);
}
