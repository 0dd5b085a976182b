#include "sync/broadcast_offsets.hpp"

#include <cmath>
#include <map>
#include <string>

#include "common/error.hpp"

namespace posefuse::sync {

std::string ble_sequence_payload(std::uint32_t sequence) {
  std::string out(4, '\0');
  for (int b = 0; b < 4; ++b) out[static_cast<std::size_t>(b)] = static_cast<char>((sequence >> (8 * b)) & 0xffu);
  return out;
}

std::uint32_t ble_sequence_from_payload(const std::string& payload) {
  if (payload.size() != 4) {
    throw_invalid("sync_event.payload",
                  "a BLE receipt carries a 4-byte sequence number, got " + std::to_string(payload.size()) + " bytes");
  }
  std::uint32_t sequence = 0;
  for (int b = 0; b < 4; ++b) {
    sequence |= static_cast<std::uint32_t>(static_cast<unsigned char>(payload[static_cast<std::size_t>(b)])) << (8 * b);
  }
  return sequence;
}

std::vector<ClockObservation> broadcast_observations(const std::vector<BroadcastReceipt>& receipts,
                                                     const std::string& device, const std::string& reference_device,
                                                     double tick_us) {
  if (!std::isfinite(tick_us) || tick_us < 0.0) throw_invalid("tick_us", "must be >= 0");
  std::map<std::int64_t, double> device_stamp, reference_stamp;
  for (std::size_t i = 0; i < receipts.size(); ++i) {
    const BroadcastReceipt& r = receipts[i];
    const std::string at = "receipts[" + std::to_string(i) + "].";
    if (!std::isfinite(r.t_device_us)) throw_invalid(at + "t_device_us", "not finite");
    std::map<std::int64_t, double>* target = r.device == device             ? &device_stamp
                                             : r.device == reference_device ? &reference_stamp
                                                                            : nullptr;
    if (target == nullptr) continue;
    if (!target->emplace(r.broadcast_id, r.t_device_us).second) {
      throw_invalid(at + "broadcast_id",
                    "device '" + r.device + "' reports broadcast " + std::to_string(r.broadcast_id) + " twice");
    }
  }
  std::vector<ClockObservation> out;
  const double sigma = tick_us / std::sqrt(6.0);
  for (const auto& [id, t_device] : device_stamp) {
    const auto ref = reference_stamp.find(id);
    if (ref == reference_stamp.end()) continue;
    out.push_back({t_device, ref->second, sigma});
  }
  if (out.empty()) {
    throw_precondition("receipts", "no broadcast was heard by both '" + device + "' and '" + reference_device + "'");
  }
  return out;
}

std::vector<ClockObservation> lower_envelope(const std::vector<ClockObservation>& observations, double bin_us) {
  if (!std::isfinite(bin_us) || bin_us <= 0.0) throw_invalid("bin_us", "must be > 0");
  if (observations.empty()) throw_invalid("observations", "no observations");
  std::map<long long, ClockObservation> best;
  for (std::size_t i = 0; i < observations.size(); ++i) {
    const ClockObservation& ob = observations[i];
    if (!std::isfinite(ob.device_us) || !std::isfinite(ob.reference_us)) {
      throw_invalid("observations[" + std::to_string(i) + "]", "not finite");
    }
    const auto bin = static_cast<long long>(std::floor(ob.device_us / bin_us));
    const auto it = best.find(bin);
    if (it == best.end() || ob.reference_us - ob.device_us < it->second.reference_us - it->second.device_us) {
      best[bin] = ob;
    }
  }
  std::vector<ClockObservation> out;
  for (const auto& [bin, ob] : best) out.push_back(ob);
  return out;
}

}  // namespace posefuse::sync
