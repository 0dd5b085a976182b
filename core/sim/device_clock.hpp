#pragma once
// Device clocks and packet loss.
//
// Every device counts time on its own oscillator (timestamps are int64 us on the device's own
// clock: docs/architecture.md, "Clocks and timestamps"). We model a device clock as an affine
// function of the camera clock,
//   t_device = offset + (1 + drift) * t_camera,
// which is what paper 1 II-G synchronises (it estimates the offset; the drift is why the
// estimate has to be refreshed in long sessions: 50 ppm is 3 ms per minute).
#include <cstdint>
#include <vector>

#include "imu/imu_sample.hpp"

namespace posefuse::sim {

struct DeviceClock {
  double offset_s = 0.0;  // device reading when the camera clock reads 0
  double drift = 0.0;     // relative rate error (50e-6 = 50 ppm fast); |drift| < 0.01

  // Rounded to the nearest microsecond. kInvalidArgument for non-finite input or clock.
  std::int64_t to_device_us(double t_camera_s) const;
  double to_camera_s(std::int64_t t_device_us) const;
};

// Samples taken every 1/rate_hz on the device's own clock, within the camera interval
// [t_camera_begin_s, t_camera_end_s]: their device timestamps (exact multiples of the period,
// in us, rounded) and the camera times at which they happen.
struct DeviceTicks {
  std::vector<std::int64_t> t_device_us;
  std::vector<double> t_camera_s;
};
DeviceTicks regular_device_ticks(const DeviceClock& clock, double rate_hz, double t_camera_begin_s,
                                 double t_camera_end_s);

// Replaces the samples' t_us (camera clock from synthesize_imu) by device timestamps;
// kInvalidArgument when the sizes differ.
void stamp_on_device_clock(std::vector<imu::ImuSample>& samples, const std::vector<std::int64_t>& t_device_us);

// Packet loss over a BLE link as a two-state (Gilbert) chain over packets: in the good state
// every packet arrives and the next one is lost with probability p; in the bad state every
// packet is lost and the state stays bad with probability 1 - 1/mean_burst_packets. p is set so
// that the long-run loss rate is loss_rate: p = loss_rate / ((1 - loss_rate) mean_burst_packets).
struct PacketLossModel {
  double loss_rate = 0.01;             // fraction of packets lost, [0, 1)
  double mean_burst_packets = 2.0;     // mean length of a run of lost packets, >= 1
  std::size_t samples_per_packet = 1;  // consecutive samples sharing one packet, >= 1
};

// For n samples: true where the sample is lost. Deterministic for a seed. kInvalidArgument
// for parameters out of range (including loss_rate > mean_burst / (1 + mean_burst), which no
// chain with that burst length reaches).
std::vector<bool> lost_samples(const PacketLossModel& model, std::size_t n, std::uint64_t seed);

// The samples whose mask entry is false; kInvalidArgument when the sizes differ.
std::vector<imu::ImuSample> drop_lost(const std::vector<imu::ImuSample>& samples, const std::vector<bool>& lost);

}  // namespace posefuse::sim
