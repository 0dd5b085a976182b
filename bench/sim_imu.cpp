// IMU simulation speed: a 60 s scripted forearm motion (1 kHz pose grid), one arm IMU at 80 Hz
// through the whole device chain (ticks, synthesis with the default error model, device
// timestamps, packet loss, batches), plus BLE receipts and a 16 kHz buzzer audio track.
//
//   build/bench/bench_sim_imu [seconds=60]
#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "bench_clock.hpp"
#include "sim/imu_device.hpp"
#include "sim/scripted_motion.hpp"

namespace {
using Clock = posefuse::bench::WallClock;
using posefuse::bench::wall_ms_since;
}  // namespace

int main(int argc, char** argv) {
  using namespace posefuse::sim;
  const double seconds = argc > 1 ? std::atof(argv[1]) : 60.0;
  if (!(seconds >= 4.0)) {
    std::fprintf(stderr, "bench_sim_imu: seconds must be >= 4\n");
    return 2;
  }
  ForearmRollingOptions rolling;
  rolling.hold_s = 1.0;
  rolling.repetitions = static_cast<int>((seconds - 2.0) / rolling.period_s);
  auto start = Clock::now();
  const ScriptedMotion motion = forearm_rolling(rolling);
  const SensorTrajectory grid = imu_trajectory(ArmGeometry(), motion);
  const double grid_ms = wall_ms_since(start);
  start = Clock::now();
  const SensorKinematics kinematics(grid);
  const double kinematics_ms = wall_ms_since(start);

  const SimDevice arm{"arm_right", {-1.5, -40e-6}};
  const SimDevice base{"base", {3.0, 20e-6}};
  ImuDeviceOptions options;
  start = Clock::now();
  const ImuDeviceResult imu = simulate_imu_device(kinematics, arm, options, 0.0, motion.duration_s);
  const double imu_ms = wall_ms_since(start);
  start = Clock::now();
  const BleBroadcastResult ble = ble_broadcast_receipts({base, arm}, BleBroadcastOptions(), 1);
  BuzzerOptions buzzer;
  buzzer.stop_device_us = base.clock.to_device_us(2.0);
  AudioOptions audio;
  audio.duration_s = motion.duration_s;
  const BuzzerResult sound = buzzer_stop(base, buzzer, audio, 1);
  const double sync_ms = wall_ms_since(start);

  std::printf("motion %.1f s: pose grid %zu poses\n", motion.duration_s, grid.p_W_m.size());
  std::printf("%-34s %10s\n", "step", "ms");
  std::printf("%-34s %10.2f\n", "scripted poses (1 kHz)", grid_ms);
  std::printf("%-34s %10.2f\n", "kinematics (5-point differences)", kinematics_ms);
  std::printf("%-34s %10.2f   (%zu samples, %zu received, %zu batches)\n", "IMU device chain (80 Hz)", imu_ms,
              imu.truth.samples.size(), imu.received.size(), imu.batches.size());
  std::printf("%-34s %10.2f   (%zu BLE events, %zu audio chunks)\n", "BLE + buzzer audio (16 kHz)", sync_ms,
              ble.events.size(), sound.audio.size());
  return 0;
}
