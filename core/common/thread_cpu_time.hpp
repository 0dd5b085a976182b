#pragma once
// CPU time of the calling thread. The development machine is shared: other load inflates wall
// time but not this thread's CPU time, so per-frame work is measured with this clock.
#include <ctime>

namespace posefuse {

// Seconds of CPU time the calling thread has used (CLOCK_THREAD_CPUTIME_ID).
inline double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

}  // namespace posefuse
