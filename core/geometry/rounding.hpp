#pragma once
// Rounding without a library call, for per-pixel loops (std::lround is not inlined on x86-64
// without SSE4.1).
#include <cstdint>

namespace posefuse::geometry {

// std::lround(x) for 0 <= x < 2^62: x - trunc(x) is exact there, and halves round up as
// lround's do (away from zero).
inline std::int64_t round_half_up(double x) {
  const auto whole = static_cast<std::int64_t>(x);
  return x - static_cast<double>(whole) >= 0.5 ? whole + 1 : whole;
}

}  // namespace posefuse::geometry
