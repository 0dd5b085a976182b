#pragma once
// One IMU device end to end: samples ticking on its own clock, the synthesized signals at those
// moments, timestamps on the device clock, packet loss, and the ImuBatch chunks that arrive.
#include <cstdint>
#include <vector>

#include "sim/device_clock.hpp"
#include "sim/imu_synth.hpp"
#include "sim/sync_signals.hpp"

namespace posefuse::sim {

struct ImuDeviceOptions {
  double rate_hz = 80.0;  // nominal rate on the device's own clock
  ImuSynthOptions synth;  // synth.nominal_rate_hz is set to rate_hz; synth.seed seeds the loss too
  PacketLossModel packet_loss;
  std::size_t samples_per_batch = 32;
};

struct ImuDeviceResult {
  std::vector<imu::ImuSample> received;  // device clock, lost samples removed
  std::vector<v1::ImuBatch> batches;     // `received` as chunks
  // Ground truth for every sample the device took, lost or not.
  ImuSynthResult truth;  // t_us on the camera clock
  DeviceTicks ticks;
  std::vector<bool> lost;
};

// Samples inside the camera interval [t_camera_begin_s, t_camera_end_s], which must lie inside
// the motion's valid range. kInvalidArgument / kOutOfRange naming the field otherwise.
ImuDeviceResult simulate_imu_device(const SensorKinematics& motion, const SimDevice& device,
                                    const ImuDeviceOptions& options, double t_camera_begin_s, double t_camera_end_s);

}  // namespace posefuse::sim
