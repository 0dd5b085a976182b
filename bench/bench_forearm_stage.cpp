// The forearm stage through the session pipeline on synthetic sessions
// (tests/session/forearm_session.hpp: scripted right arm, IMUs on their own clocks, buzzer and
// BLE sync, rendered strap), for several occlusion lengths and seeds: accuracy against the truth
// and the stage's time. Prints one table row per occlusion length (3 seeds pooled: RMS over all
// samples, max over all).
//
// Not Table I of paper 1: that needs the finished simulator (body-driven IMUs, RGB with strap,
// the paper's protocol and the mocap clips) and is run by its own benchmark.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

#include "bench_clock.hpp"
#include "forearm_session.hpp"
#include "session/pipeline.hpp"
#include "session/stages/default_stages.hpp"

namespace {

using namespace posefuse;

struct Sink : session::ResultSink {
  void emit(v1::FitResult&& result) override { results.push_back(std::move(result)); }
  std::vector<v1::FitResult> results;
};

struct Pooled {
  double orientation_sq = 0.0, orientation_max = 0.0;
  std::size_t orientation_n = 0;
  double visible_sq = 0.0;
  std::size_t visible_n = 0;
  double predicted_max = 0.0;
  std::map<int, double> recovered_sq, recovered_max;
  std::map<int, std::size_t> recovered_n;
  double stage_s = 0.0, session_s = 0.0;
};

}  // namespace

int main() {
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  std::printf("forearm stage on synthetic sessions (10 s, occlusion from 5.5 s; 3 seeds per row)\n\n");
  std::printf(
      "| gap s | orient. RMS deg | orient. max deg | visible RMS mm | live max mm | paper RMS mm | paper max mm "
      "| smoother RMS mm | smoother max mm | pipeline CPU ms per s |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  for (const double gap_s : {0.5, 0.9, 1.5}) {
    Pooled pooled;
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      session::testing::ForearmSessionOptions options;
      options.duration_s = 10.0;
      options.occlusion_begin_s = 5.5;
      options.occlusion_end_s = 5.5 + gap_s;
      options.seed = seed;
      session::testing::ForearmSessionTruth truth;
      const auto chunks = session::testing::make_forearm_session(options, &truth);
      Sink sink;
      const double cpu0 = bench::thread_cpu_seconds();
      session::SessionPipeline pipeline(session::make_default_stages(), sink);
      for (const auto& chunk : chunks) pipeline.push(chunk);
      pipeline.close();
      pooled.stage_s += bench::thread_cpu_seconds() - cpu0;
      pooled.session_s += options.duration_s;
      const auto e = session::testing::evaluate_forearm_results(truth, sink.results);
      pooled.orientation_sq +=
          e.orientation_rms_rad * e.orientation_rms_rad * static_cast<double>(e.orientation_samples);
      pooled.orientation_n += e.orientation_samples;
      pooled.orientation_max = std::max(pooled.orientation_max, e.orientation_max_rad);
      pooled.visible_sq += e.visible_rms_m * e.visible_rms_m * static_cast<double>(e.visible_frames);
      pooled.visible_n += e.visible_frames;
      pooled.predicted_max = std::max(pooled.predicted_max, e.predicted_max_m);
      for (const auto& [method, r] : e.recovered) {
        pooled.recovered_sq[method] += r.rms_m * r.rms_m * static_cast<double>(r.samples);
        pooled.recovered_n[method] += r.samples;
        pooled.recovered_max[method] = std::max(pooled.recovered_max[method], r.max_m);
      }
    }
    const auto rms = [](double sq, std::size_t n) { return n > 0 ? std::sqrt(sq / static_cast<double>(n)) : NAN; };
    const int paper = v1::RecoveredSegment::PAPER, smoother = v1::RecoveredSegment::SMOOTHER;
    std::printf("| %.1f | %.2f | %.2f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f |\n", gap_s,
                rms(pooled.orientation_sq, pooled.orientation_n) / kDeg, pooled.orientation_max / kDeg,
                1e3 * rms(pooled.visible_sq, pooled.visible_n), 1e3 * pooled.predicted_max,
                1e3 * rms(pooled.recovered_sq[paper], pooled.recovered_n[paper]), 1e3 * pooled.recovered_max[paper],
                1e3 * rms(pooled.recovered_sq[smoother], pooled.recovered_n[smoother]),
                1e3 * pooled.recovered_max[smoother], 1e3 * pooled.stage_s / pooled.session_s);
  }
  std::printf(
      "\npipeline CPU: thread CPU time of the whole pipeline (validation, IMU orientation stage, forearm\n"
      "stage incl. PNG decoding of 480x270 colour and 200x166 depth frames) per second of session.\n");
  return 0;
}
