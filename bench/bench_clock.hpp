#pragma once
// Clocks shared by the benchmark programs.
#include <chrono>

#include "common/thread_cpu_time.hpp"

namespace posefuse::bench {

// CPU time of the calling thread, seconds. Benchmarks report it beside wall time because the
// development machine is shared: other load inflates wall time but not this thread's CPU time.
using posefuse::thread_cpu_seconds;

using WallClock = std::chrono::steady_clock;

// Wall-clock milliseconds since `start`.
inline double wall_ms_since(WallClock::time_point start) {
  return std::chrono::duration<double, std::milli>(WallClock::now() - start).count();
}

}  // namespace posefuse::bench
