#include "sim/imu_device.hpp"

namespace posefuse::sim {

ImuDeviceResult simulate_imu_device(const SensorKinematics& motion, const SimDevice& device,
                                    const ImuDeviceOptions& options, double t_camera_begin_s, double t_camera_end_s) {
  ImuDeviceResult out;
  out.ticks = regular_device_ticks(device.clock, options.rate_hz, t_camera_begin_s, t_camera_end_s);
  ImuSynthOptions synth = options.synth;
  synth.nominal_rate_hz = options.rate_hz;
  out.truth = synthesize_imu(motion, out.ticks.t_camera_s, synth);
  std::vector<imu::ImuSample> on_device = out.truth.samples;
  stamp_on_device_clock(on_device, out.ticks.t_device_us);
  out.lost = lost_samples(options.packet_loss, on_device.size(), synth.seed);
  out.received = drop_lost(on_device, out.lost);
  out.batches = imu_batches(device.device_id, out.received, options.samples_per_batch);
  return out;
}

}  // namespace posefuse::sim
