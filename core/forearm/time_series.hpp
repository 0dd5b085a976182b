#pragma once
// Lookups in time series sorted by t_us (the forearm's IMU samples, track samples, anchors).
#include <algorithm>
#include <cstddef>
#include <cstdint>

namespace posefuse::forearm {

inline constexpr std::size_t kNoIndex = static_cast<std::size_t>(-1);

// Index of the last sample at or before t_us; kNoIndex when none.
template <class Series>
std::size_t index_at_or_before(const Series& series, std::int64_t t_us) {
  const auto it =
      std::upper_bound(series.begin(), series.end(), t_us, [](std::int64_t t, const auto& s) { return t < s.t_us; });
  return it == series.begin() ? kNoIndex : static_cast<std::size_t>(it - series.begin() - 1);
}

// The samples with t_us in [t0_us, t1_us].
template <class Series>
Series slice(const Series& series, std::int64_t t0_us, std::int64_t t1_us) {
  Series out;
  for (const auto& s : series) {
    if (s.t_us >= t0_us && s.t_us <= t1_us) out.push_back(s);
  }
  return out;
}

}  // namespace posefuse::forearm
