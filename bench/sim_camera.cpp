// Camera stream simulation speed at the Kinect v2's full 512 x 424: arm raising at 30 Hz,
// each frame posed, rendered with the room, noised, encoded (zstd depth, PNG body index) and
// given a camera skeleton.
//
//   build/bench/bench_sim_camera [seconds=10]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>

#include "bench_clock.hpp"
#include "sim/camera_session.hpp"

int main(int argc, char** argv) {
  using namespace posefuse;
  const double seconds = argc > 1 ? std::atof(argv[1]) : 10.0;
  if (!(seconds > 0.0)) {
    std::fprintf(stderr, "bench_sim_camera: seconds must be > 0\n");
    return 2;
  }
  sim::CameraSessionOptions options;  // full-resolution Kinect v2 intrinsics
  options.duration_s = seconds;
  const body::PoseLayout layout = body::PoseLayout::full_body();
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start_ms = 1e3 * posefuse::bench::thread_cpu_seconds();
  const sim::CameraSessionResult r =
      sim::simulate_camera_session(options, layout, sim::arm_raising_sequence(layout, 4.0));
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  const double cpu_ms = 1e3 * posefuse::bench::thread_cpu_seconds() - cpu_start_ms;
  std::size_t bytes = 0;
  for (const auto& c : r.chunks) bytes += c.ByteSizeLong();
  std::printf(
      "%zu frames of %dx%d: wall %.1f ms (%.2f ms per frame), thread CPU %.1f ms (%.2f ms per frame), "
      "%.1f MB of chunks\n",
      r.t_us.size(), options.intrinsics.width, options.intrinsics.height, ms, ms / r.t_us.size(), cpu_ms,
      cpu_ms / r.t_us.size(), bytes / 1e6);
  return 0;
}
