// Speed of the faithful quaternion Kalman orientation filter (paper 1, II-D) on one core.
// Target (docs/architecture.md, "Speed targets"): >= 5 million samples/s. Also counts heap
// allocations per sample, which must be zero for update().
//   build/bench/bench_kalman_speed [samples]
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <new>
#include <random>
#include <string>
#include <vector>

#include "bench_clock.hpp"
#include "imu/kalman_orientation_filter.hpp"

namespace {
std::atomic<long> g_allocations{0};
}

// Count every heap allocation of the process (the filter must make none per sample).
void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

using posefuse::imu::ImuSample;
using posefuse::imu::KalmanOrientationFilter;
using posefuse::imu::Quat;
using posefuse::imu::Vec3;

namespace {

// 80 Hz readings of a sensor turning at a slowly varying rate, with noise and bias.
std::vector<ImuSample> make_stream(std::size_t count, bool with_mag) {
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, 1.0);
  const Vec3 g_W(0, 0, 9.81);
  const Vec3 m_W(21.0, 0.0, -43.0);
  std::vector<ImuSample> out(count);
  Quat W_from_A = Quat::Identity();
  for (std::size_t i = 0; i < count; ++i) {
    const double t = static_cast<double>(i) / 80.0;
    const Vec3 rate(1.5 * std::sin(2.2 * t), 1.2 * std::sin(3.1 * t + 1), 0.9 * std::cos(1.4 * t));
    W_from_A = (W_from_A * Quat(Eigen::AngleAxisd(rate.norm() / 80.0, rate.normalized()))).normalized();
    ImuSample& s = out[i];
    s.t_us = static_cast<std::int64_t>(i) * 12500;
    s.gyr_rad_s = rate + Vec3(0.01, -0.02, 0.005) + 0.005 * Vec3(noise(rng), noise(rng), noise(rng));
    s.acc_m_s2 = W_from_A.conjugate() * g_W + 0.05 * Vec3(noise(rng), noise(rng), noise(rng));
    s.mag_uT = with_mag ? Vec3(W_from_A.conjugate() * m_W + 0.3 * Vec3(noise(rng), noise(rng), noise(rng)))
                        : Vec3::Constant(std::nan(""));
    if (!with_mag && i == 0) s.mag_uT = W_from_A.conjugate() * m_W;  // the start needs one reading
  }
  return out;
}

struct Timing {
  double best_s = 1e300;  // thread CPU time
  double median_s = 0.0;  // thread CPU time
  double best_wall_s = 0.0;
  double allocations_per_sample = 0.0;
};

template <typename Run>
Timing time_runs(std::size_t samples, int repeats, Run run) {
  std::vector<double> seconds;
  std::vector<double> wall_seconds;
  long allocations = 0;
  for (int r = 0; r < repeats; ++r) {
    const long before = g_allocations.load();
    const auto start = std::chrono::steady_clock::now();
    const double cpu_start = posefuse::bench::thread_cpu_seconds();
    run();
    seconds.push_back(posefuse::bench::thread_cpu_seconds() - cpu_start);
    const auto stop = std::chrono::steady_clock::now();
    allocations = g_allocations.load() - before;
    wall_seconds.push_back(std::chrono::duration<double>(stop - start).count());
  }
  std::sort(seconds.begin(), seconds.end());
  Timing t;
  t.best_wall_s = *std::min_element(wall_seconds.begin(), wall_seconds.end());
  t.best_s = seconds.front();
  t.median_s = seconds[seconds.size() / 2];
  t.allocations_per_sample = static_cast<double>(allocations) / static_cast<double>(samples);
  return t;
}

void print_row(const char* name, std::size_t samples, const Timing& t) {
  const double n = static_cast<double>(samples);
  std::printf("| %-44s | %9zu | %8.2f | %8.2f | %8.2f | %8.1f | %10.2e |\n", name, samples, 1e-6 * n / t.best_s,
              1e-6 * n / t.median_s, 1e-6 * n / t.best_wall_s, 1e9 * t.best_s / n, t.allocations_per_sample);
}

}  // namespace

int main(int argc, char** argv) {
  const std::size_t samples = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 2'000'000;
  const int repeats = 7;
  const std::vector<ImuSample> with_mag = make_stream(samples, true);
  const std::vector<ImuSample> without_mag = make_stream(samples, false);
  std::vector<Quat> out(samples);
  double checksum = 0.0;

  std::printf("bench_kalman_speed: %zu samples, best and median of %d runs, one thread\n\n", samples, repeats);
  std::printf(
      "M/s: million samples per second of thread CPU time (best, median) and of wall\n"
      "time (best); ns/samp from the best CPU time; allocs/smp: heap allocations per sample.\n\n");
  std::printf("| %-44s | %9s | %8s | %8s | %8s | %8s | %10s |\n", "case", "samples", "best M/s", "med M/s", "wall M/s",
              "ns/samp", "allocs/smp");
  const std::string dash(10, '-');
  std::printf("|%s|%s|%s|%s|%s|%s|%s|\n", std::string(46, '-').c_str(), std::string(11, '-').c_str(), dash.c_str(),
              dash.c_str(), dash.c_str(), dash.c_str(), std::string(12, '-').c_str());

  for (const bool mag : {true, false}) {
    const std::vector<ImuSample>& stream = mag ? with_mag : without_mag;
    const Timing per_sample = time_runs(samples, repeats, [&] {
      KalmanOrientationFilter filter;
      for (std::size_t i = 0; i < samples; ++i) out[i] = filter.update(stream[i]);
      checksum += out.back().w();
    });
    print_row(mag ? "update() per sample, predict + correct" : "update() per sample, predict only (no mag)", samples,
              per_sample);
  }
  const Timing batch = time_runs(samples, repeats, [&] {
    KalmanOrientationFilter filter;
    const std::vector<Quat> result = filter.process(with_mag);
    checksum += result.back().w();
  });
  print_row("process() whole stream (validate + run)", samples, batch);
  std::printf("\n(checksum %.6f)\n", checksum);
  return 0;
}
