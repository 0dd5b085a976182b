// Paper 1's Table I (III, IV) on simulated sessions: the paper's protocol (calibration pose,
// forearm behind the head, in front of the belly, behind the back) and each mocap clip behind a
// calibration hold, simulated with the body-driven right-forearm IMU (noise, own clocks, buzzer,
// BLE), run through SessionPipeline(make_default_stages()) and scored against the simulator's
// truth: forearm orientation error (eqs. 14-15) of the camera SDK vs the fusion, IMU position
// error of the SDK (eq. 16) vs the fusion with the paper's recovery and with the smoother (and the
// causal live estimate), RMS and maximum over all frames and inside gaps only. Writes
// table1_<session>.png (Figs. 4-6: errors and x_K over time, occluded frames grey).
//
//   build/bench/bench_table1 [mocap folder=../shared/data/mocap] [image folder=docs/images]
//                            [longest clip s=20]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "bench_clock.hpp"
#include "common/error.hpp"
#include "session/pipeline.hpp"
#include "session/stages/default_stages.hpp"
#include "sim/bvh.hpp"
#include "sim/bvh_motion.hpp"
#include "sim/exercises.hpp"
#include "table1/calibration_prefix.hpp"
#include "table1/table1_errors.hpp"
#include "table1/table1_session.hpp"
#include "table1/time_plot.hpp"

namespace {

using namespace posefuse;
namespace fs = std::filesystem;

struct Sink : session::ResultSink {
  void emit(v1::FitResult&& result) override { results.push_back(std::move(result)); }
  std::vector<v1::FitResult> results;
};

struct Named {
  std::string name;
  sim::BodyMotion motion;
  bool sdk_joint_errors = true;
  // The stage's forearm.axis and forearm.shoulder_sphere: "sdk" and "on" are the stage before the
  // depth axis (paper 1's forearm axis from the SDK joints).
  std::string axis = "depth";
  std::string shoulder_sphere = "off";
  // The stage's forearm.upper_arm: "sdk" takes the calibration pose's arm plane (the roll about the
  // forearm) from the SDK shoulder, as paper 1 does.
  std::string upper_arm = "depth";
};

std::size_t gap_count(const std::vector<bool>& occluded) {
  std::size_t gaps = 0;
  for (std::size_t i = 0; i < occluded.size(); ++i) gaps += occluded[i] && (i == 0 || !occluded[i - 1]);
  return gaps;
}

void print_row(const char* quantity, const std::vector<std::vector<double>>& columns, const std::vector<bool>& mask,
               bool max, double scale, const char* paper) {
  std::printf("| %s |", quantity);
  for (const auto& c : columns) {
    const eval::ErrorSummary s = eval::summarize_errors(c, mask);
    std::printf(" %.4g (%zu) |", scale * (max ? s.max : s.rms), s.count);
  }
  std::printf(" %s |\n", paper);
}

// One line of the closing summary: orientation RMS / max (SDK, fusion), position RMS / max (SDK,
// paper recovery, smoother).
struct Summary {
  std::string name;
  eval::ErrorSummary orientation[2], position[3];
};

Summary run(const Named& session_motion, const fs::path& image_folder, double longest_s, std::uint64_t seed) {
  bench::Table1SessionOptions options;
  options.seed = seed;
  options.strap.F_from_A = geometry::quat_from_rotation_vector(geometry::Vec3(0.2, -0.1, 0.3));
  options.duration_s = longest_s;
  options.sdk_joint_errors = session_motion.sdk_joint_errors;
  double hold_begin = 0.0, hold_end = 0.0;
  for (const sim::MotionPhase& p : session_motion.motion.phases) {
    if (p.name == "calibration_hold") {
      hold_begin = p.begin_s;
      hold_end = p.end_s;
      break;
    }
  }
  options.calibration_end_s = hold_end;
  const double cpu0 = bench::thread_cpu_seconds();
  const bench::Table1Session session = bench::simulate_table1_session(session_motion.motion, options);
  const double cpu1 = bench::thread_cpu_seconds();
  Sink sink;
  session::SessionPipeline pipeline(session::make_default_stages(), sink);
  for (v1::SessionChunk chunk : session.chunks) {
    if (chunk.has_header()) {
      auto& stage_options = *chunk.mutable_header()->mutable_options();
      stage_options["forearm.axis"] = session_motion.axis;
      stage_options["forearm.shoulder_sphere"] = session_motion.shoulder_sphere;
      stage_options["forearm.upper_arm"] = session_motion.upper_arm;
    }
    pipeline.push(chunk);
  }
  pipeline.close();
  const double cpu2 = bench::thread_cpu_seconds();
  for (const v1::FitResult& r : sink.results) {
    if (r.has_warning()) std::printf("warning: %s\n", r.warning().ShortDebugString().c_str());
  }
  const bench::Table1Series s = bench::table1_series(session, sink.results, hold_begin, hold_end,
                                                     options.strap.strap_to_elbow_m, session.d_sw_m);
  std::size_t occluded = 0;
  for (const bool o : s.occluded) occluded += o;
  std::printf("\n### %s (seed %llu): %.1f s, %zu frames, %zu occluded in %zu gaps; calibration hold %.1f-%.1f s; "
              "CPU s: simulation %.1f, pipeline %.1f\n\n",
              session_motion.name.c_str(), static_cast<unsigned long long>(seed), s.t_s.back(), s.t_s.size(), occluded, gap_count(s.occluded), hold_begin,
              hold_end, cpu1 - cpu0, cpu2 - cpu1);
  std::printf("| error (frames) | SDK | fusion, paper recovery | fusion, smoother | fusion, live | paper 1 SDK -> fusion |\n");
  std::printf("|---|---|---|---|---|---|\n");
  const std::vector<std::vector<double>> orientation = {s.sdk_orientation_deg, s.fusion_orientation_deg,
                                                        s.fusion_orientation_deg, s.fusion_orientation_deg};
  const std::vector<std::vector<double>> position = {s.sdk_position_m, s.paper_position_m, s.smoother_position_m,
                                                     s.live_position_m};
  const std::vector<bool> all;
  print_row("orientation RMS deg", orientation, all, false, 1.0, "84.25 -> 11.34");
  print_row("orientation max deg", orientation, all, true, 1.0, "179.79 -> 17.43");
  print_row("position RMS m", position, all, false, 1.0, "0.07032 -> 0.04071");
  print_row("position max m", position, all, true, 1.0, "0.23921 -> 0.14098");
  print_row("in gaps: orientation RMS deg", orientation, s.occluded, false, 1.0, "");
  print_row("in gaps: orientation max deg", orientation, s.occluded, true, 1.0, "");
  print_row("in gaps: position RMS m", position, s.occluded, false, 1.0, "");
  print_row("in gaps: position max m", position, s.occluded, true, 1.0, "");
  std::size_t truth_visible = 0, accepted = 0;
  for (std::size_t f = 0; f < s.t_s.size(); ++f) {
    truth_visible += !s.occluded[f];
    accepted += !s.occluded[f] && s.stage_visible[f];
  }
  std::printf("the stage accepted the strap (eq. 10, II-J tests) at %zu of the %zu frames where it is visible\n", accepted,
              truth_visible);
  if (s.sdk_orientation_missing > 0) std::printf("(SDK gave no wrist orientation at %zu frames)\n", s.sdk_orientation_missing);

  const cv::Scalar red(40, 40, 220), blue(200, 90, 20), orange(20, 140, 240), black(0, 0, 0);
  const fs::path png = image_folder / ("table1_" + session_motion.name + ".png");
  const bool written = bench::write_time_plot(
      png.string(), s.t_s, s.occluded,
      {{"orientation error, deg (eqs. 14-15; Fig. 4)", {{"SDK", s.sdk_orientation_deg, red}, {"fusion", s.fusion_orientation_deg, blue}}},
       {"IMU position error, m (Fig. 5)",
        {{"SDK (eq. 16)", s.sdk_position_m, red}, {"paper recovery", s.paper_position_m, orange},
         {"smoother", s.smoother_position_m, blue}}},
       {"IMU x_K, m (Fig. 6)",
        {{"truth", s.true_x_m, black}, {"SDK (eq. 16)", s.sdk_x_m, red}, {"paper recovery", s.paper_x_m, orange},
         {"smoother", s.smoother_x_m, blue}}}});
  std::printf("plot: %s%s\n", png.string().c_str(), written ? "" : " (NOT written)");
  Summary summary{session_motion.name, {}, {}};
  for (std::size_t i = 0; i < 2; ++i) summary.orientation[i] = eval::summarize_errors(orientation[i]);
  for (std::size_t i = 0; i < 3; ++i) summary.position[i] = eval::summarize_errors(position[i]);
  return summary;
}

}  // namespace

int main(int argc, char** argv) {
  const fs::path mocap = argc > 1 ? fs::path(argv[1]) : fs::path("../shared/data/mocap");
  const fs::path images = argc > 2 ? fs::path(argv[2]) : fs::path("docs/images");
  const double longest_s = argc > 3 ? std::stod(argv[3]) : 20.0;
  std::vector<Named> sessions;
  sim::ExerciseOptions protocol;
  protocol.repetitions = 1;
  sessions.push_back({"protocol", sim::make_exercise("forearm_protocol", protocol)});
  // Paper 1's method: the forearm axis from the SDK's elbow and wrist (same SDK errors and seed).
  sessions.push_back(
      {"protocol_paper_axis", sim::make_exercise("forearm_protocol", protocol), true, "sdk", "on", "sdk"});
  // The depth forearm axis with the roll from the SDK shoulder (the stage before forearm.upper_arm).
  sessions.push_back(
      {"protocol_sdk_upper_arm", sim::make_exercise("forearm_protocol", protocol), true, "depth", "off", "sdk"});
  // Diagnostic: the same session with an error-free SDK skeleton.
  sessions.push_back({"protocol_exact_sdk", sim::make_exercise("forearm_protocol", protocol), false});
  if (fs::is_directory(mocap)) {
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(mocap)) {
      if (entry.is_regular_file() && entry.path().extension() == ".bvh") files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    const sim::BodyMotion calibration = sim::make_exercise("calibration_pose", protocol);
    for (const fs::path& file : files) {
      try {
        sessions.push_back({file.stem().string(), bench::with_calibration_prefix(
                                                      calibration, sim::bvh_motion(sim::load_bvh(file)))});
      } catch (const Error& e) {
        std::printf("%s: skipped (%s)\n", file.string().c_str(), e.what());
      }
    }
  } else {
    std::printf("%s not found: the protocol only\n", mocap.string().c_str());
  }
  std::printf("paper 1 Table I on simulated sessions; sessions cut at %.0f s\n", longest_s);
  std::vector<Summary> summaries;
  std::uint64_t seed = 0;
  for (const Named& s : sessions) {
    // Every session draws its own SDK biases and noise; the variants (paper axis, exact SDK) repeat
    // their predecessor's.
    if (s.sdk_joint_errors && s.axis == "depth" && s.upper_arm == "depth") ++seed;
    try {
      summaries.push_back(run(s, images, longest_s, seed));
    } catch (const Error& e) {
      std::printf("\n### %s: failed: %s\n", s.name.c_str(), e.what());
    }
  }
  std::printf("\n### summary (all frames; targets on the protocol: orientation RMS <= 5 deg, smoother position RMS <= "
              "0.02 m and max <= 0.06 m)\n\n");
  std::printf("| session | orient. RMS deg SDK / fusion | orient. max deg SDK / fusion | position RMS m SDK / paper / "
              "smoother | position max m SDK / paper / smoother |\n|---|---|---|---|---|\n");
  std::printf("| paper 1 | 84.25 / 11.34 | 179.79 / 17.43 | 0.0703 / 0.0407 / - | 0.2392 / 0.1410 / - |\n");
  for (const Summary& u : summaries) {
    std::printf("| %s | %.2f / %.2f | %.2f / %.2f | %.4f / %.4f / %.4f | %.4f / %.4f / %.4f |\n", u.name.c_str(),
                u.orientation[0].rms, u.orientation[1].rms, u.orientation[0].max, u.orientation[1].max,
                u.position[0].rms, u.position[1].rms, u.position[2].rms, u.position[0].max, u.position[1].max,
                u.position[2].max);
  }
  return 0;
}
