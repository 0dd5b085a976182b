#pragma once
// Broadcast-based synchronisation (paper 1, II-G.2): the host sends BLE advertisements; each IMU
// that hears one stamps the receipt on its own clock. Devices hearing the same advertisement
// hear it at the same instant, so two receipt stamps of one broadcast are one clock observation.
// Receipts are lost (BLE is unreliable) and some are late (a stamp taken after a busy radio
// slot): fit_linear_clock rejects those as outliers.
#include <cstdint>
#include <string>
#include <vector>

#include "sync/buzzer_stop.hpp"

namespace posefuse::sync {

inline constexpr double kBleClockTickUs = 312.5;  // BLE clock resolution (II-G.2)

// Payload of a BLE_BROADCAST_RECEIPT sync event (docs/simulator.md): the broadcast's
// sequence number, 4 bytes uint32 little-endian. The decoder throws posefuse::Error
// kInvalidArgument "sync_event.payload" unless the payload is 4 bytes.
std::string ble_sequence_payload(std::uint32_t sequence);
std::uint32_t ble_sequence_from_payload(const std::string& payload);

struct BroadcastReceipt {
  std::int64_t broadcast_id = 0;  // which advertisement
  std::string device;             // who heard it
  double t_device_us = 0.0;       // receipt stamp on that device's clock
};

// One observation device -> reference_device per broadcast heard by both. Each stamp is
// quantised to `tick_us`, so the difference has sigma tick_us / sqrt(6) (two uniform errors).
// Throws posefuse::Error kInvalidArgument "receipts[i].*" on a non-finite stamp or a device that
// reports one broadcast twice; kFailedPrecondition "receipts" when no broadcast was heard by both.
std::vector<ClockObservation> broadcast_observations(const std::vector<BroadcastReceipt>& receipts,
                                                     const std::string& device, const std::string& reference_device,
                                                     double tick_us = kBleClockTickUs);

// Host receipt time vs the device's own timestamp of the same packet: the host sees it later by
// a latency that is never negative but varies. Keeps, per `bin_us` of device time, the
// observation with the smallest latency (the lower envelope) for fit_linear_clock; the fitted
// offset then includes the minimum latency, which no receipt can reveal.
// Throws posefuse::Error kInvalidArgument "bin_us" if not > 0, "observations" when empty.
std::vector<ClockObservation> lower_envelope(const std::vector<ClockObservation>& observations, double bin_us);

}  // namespace posefuse::sync
