#include "sim/device_clock.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.hpp"
#include "sim/option_checks.hpp"
#include "sim/sim_rng.hpp"

namespace posefuse::sim {
namespace {

void check_clock(const DeviceClock& c) {
  require_finite(c.offset_s, "clock.offset_s");
  if (!(std::abs(c.drift) < 0.01)) {
    throw_invalid("clock.drift", "must be finite with |drift| < 0.01, got " + std::to_string(c.drift));
  }
}

}  // namespace

std::int64_t DeviceClock::to_device_us(double t_camera_s) const {
  check_clock(*this);
  require_finite(t_camera_s, "t_camera_s");
  return std::llround((offset_s + (1.0 + drift) * t_camera_s) * 1e6);
}

double DeviceClock::to_camera_s(std::int64_t t_device_us) const {
  check_clock(*this);
  return (1e-6 * static_cast<double>(t_device_us) - offset_s) / (1.0 + drift);
}

DeviceTicks regular_device_ticks(const DeviceClock& clock, double rate_hz, double t_camera_begin_s,
                                 double t_camera_end_s) {
  check_clock(clock);
  require_positive(rate_hz, "rate_hz");
  require_interval(t_camera_begin_s, t_camera_end_s, "t_camera_end_s");
  const double period_s = 1.0 / rate_hz;
  const double device_begin_s = clock.offset_s + (1.0 + clock.drift) * t_camera_begin_s;
  const double device_end_s = clock.offset_s + (1.0 + clock.drift) * t_camera_end_s;
  DeviceTicks ticks;
  for (auto k = static_cast<std::int64_t>(std::ceil(device_begin_s / period_s - 1e-9));
       static_cast<double>(k) * period_s <= device_end_s + 1e-12; ++k) {
    const double device_s = static_cast<double>(k) * period_s;
    const double camera_s = (device_s - clock.offset_s) / (1.0 + clock.drift);
    if (camera_s < t_camera_begin_s || camera_s > t_camera_end_s) continue;  // rounding at the ends
    ticks.t_device_us.push_back(std::llround(device_s * 1e6));
    ticks.t_camera_s.push_back(camera_s);
  }
  return ticks;
}

void stamp_on_device_clock(std::vector<imu::ImuSample>& samples, const std::vector<std::int64_t>& t_device_us) {
  if (samples.size() != t_device_us.size()) {
    throw_invalid("t_device_us", std::to_string(t_device_us.size()) + " timestamps for " +
                                     std::to_string(samples.size()) + " samples");
  }
  for (std::size_t k = 0; k < samples.size(); ++k) samples[k].t_us = t_device_us[k];
}

std::vector<bool> lost_samples(const PacketLossModel& model, std::size_t n, std::uint64_t seed) {
  const double loss = model.loss_rate;
  const double burst = model.mean_burst_packets;
  if (!(loss >= 0 && loss < 1)) throw_invalid("packet_loss.loss_rate", "must be in [0, 1)");
  if (!(burst >= 1) || !std::isfinite(burst)) throw_invalid("packet_loss.mean_burst_packets", "must be >= 1");
  if (model.samples_per_packet == 0) throw_invalid("packet_loss.samples_per_packet", "must be >= 1");
  const double enter_bad = loss / ((1.0 - loss) * burst);
  if (enter_bad > 1.0) {
    throw_invalid("packet_loss.loss_rate",
                  "too high for bursts of " + std::to_string(burst) + " packets (at most burst / (1 + burst))");
  }
  const double stay_bad = 1.0 - 1.0 / burst;
  SimRng rng(seed, "packet_loss");
  bool bad = rng.uniform() < loss;  // start in the stationary distribution
  std::vector<bool> lost(n, false);
  for (std::size_t first = 0; first < n; first += model.samples_per_packet) {
    const std::size_t end = std::min(n, first + model.samples_per_packet);
    for (std::size_t k = first; k < end; ++k) lost[k] = bad;
    bad = rng.uniform() < (bad ? stay_bad : enter_bad);
  }
  return lost;
}

std::vector<imu::ImuSample> drop_lost(const std::vector<imu::ImuSample>& samples, const std::vector<bool>& lost) {
  if (samples.size() != lost.size()) {
    throw_invalid("lost", std::to_string(lost.size()) + " flags for " + std::to_string(samples.size()) + " samples");
  }
  std::vector<imu::ImuSample> kept;
  kept.reserve(samples.size());
  for (std::size_t k = 0; k < samples.size(); ++k) {
    if (!lost[k]) kept.push_back(samples[k]);
  }
  return kept;
}

}  // namespace posefuse::sim
