#pragma once
// A percentile of sorted values, by linear interpolation between the closest ranks.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace posefuse {

// p in [0, 1]; `sorted` ascending and not empty.
inline double percentile(const std::vector<double>& sorted, double p) {
  const double position = p * static_cast<double>(sorted.size() - 1);
  const auto below = static_cast<std::size_t>(std::floor(position));
  const std::size_t above = std::min(below + 1, sorted.size() - 1);
  const double fraction = position - static_cast<double>(below);
  return sorted[below] + fraction * (sorted[above] - sorted[below]);
}

}  // namespace posefuse
