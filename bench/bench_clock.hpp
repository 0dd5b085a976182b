#pragma once
// Clocks shared by the benchmark programs.
#include <chrono>
#include <ctime>

namespace posefuse::bench {

// CPU time of the calling thread, seconds. Benchmarks report it beside wall time because the
// development machine is shared: other load inflates wall time but not this thread's CPU time.
inline double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

using WallClock = std::chrono::steady_clock;

// Wall-clock milliseconds since `start`.
inline double wall_ms_since(WallClock::time_point start) {
  return std::chrono::duration<double, std::milli>(WallClock::now() - start).count();
}

}  // namespace posefuse::bench
