// Speed of a whole simulated session (posefuse-sim's work without the file system):
//   build/bench/bench_sim_session [seconds=60] [threads=2] [motion=arm_raising]
// Prints thread CPU seconds per part of the work (summed over threads) and the wall time.
// Chunks are serialised (as a chunk file would) and counted, not written.
#include <unistd.h>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "bench_clock.hpp"
#include "sim/ground_truth_files.hpp"
#include "sim/sim_session.hpp"

namespace {

class CountingSink : public posefuse::session::ChunkSink {
 public:
  void write(const posefuse::session::SessionChunk& chunk) override {
    chunk.SerializeToString(&buffer_);
    bytes += buffer_.size();
    ++chunks;
  }
  void finish() override {}
  std::uint64_t bytes = 0, chunks = 0;

 private:
  std::string buffer_;
};

}  // namespace

int main(int argc, char** argv) {
  using namespace posefuse;
  sim::SimSessionOptions options;
  options.duration_s = argc > 1 ? std::atof(argv[1]) : 60.0;
  options.threads = argc > 2 ? std::atoi(argv[2]) : 2;
  if (argc > 3) options.motion = argv[3];
  CountingSink sink;
  const auto start = bench::WallClock::now();
  const double cpu_start = bench::thread_cpu_seconds();
  sim::SimTruth truth = sim::simulate_session(options, sink);
  const double wall_ms = bench::wall_ms_since(start);
  const double main_cpu = bench::thread_cpu_seconds() - cpu_start;

  const auto gt = std::filesystem::temp_directory_path() / ("bench_sim_session_gt_" + std::to_string(::getpid()));
  const double gt_cpu_start = bench::thread_cpu_seconds();
  const auto gt_start = bench::WallClock::now();
  sim::write_ground_truth(truth, gt);
  const double gt_wall_ms = bench::wall_ms_since(gt_start);
  const double gt_cpu = bench::thread_cpu_seconds() - gt_cpu_start;
  std::filesystem::remove_all(gt);

  std::printf("session: %.0f s, %zu frames, %llu chunks, %.1f MB serialised, threads %d\n\n", options.duration_s,
              truth.frames.size(), static_cast<unsigned long long>(sink.chunks), sink.bytes / 1e6, options.threads);
  std::printf("| part | CPU s | CPU ms per frame |\n| --- | --- | --- |\n");
  double total = 0;
  for (const auto& [part, seconds] : truth.cpu_s) {
    std::printf("| %s | %.2f | %.2f |\n", part.c_str(), seconds,
                1e3 * seconds / static_cast<double>(truth.frames.size()));
    total += seconds;
  }
  std::printf("| **total CPU (all threads)** | %.2f | %.2f |\n", total,
              1e3 * total / static_cast<double>(truth.frames.size()));
  std::printf("| gt/ files (written to %s) | %.2f | |\n\n", std::filesystem::temp_directory_path().c_str(), gt_cpu);
  std::printf("wall: simulation %.2f s (main thread CPU %.2f s), gt/ %.2f s; real time factor %.2f\n", wall_ms / 1e3,
              main_cpu, gt_wall_ms / 1e3, options.duration_s / ((wall_ms + gt_wall_ms) / 1e3));
  return 0;
}
