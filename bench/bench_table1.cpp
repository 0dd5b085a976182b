// Paper 1's Table I (III, IV) on simulated sessions: the paper's protocol (calibration pose,
// forearm behind the head, in front of the belly, behind the back) and each mocap clip behind a
// calibration hold, run through SessionPipeline(make_default_stages()) and scored against the
// simulator's truth: forearm orientation error (eqs. 14-15) of the camera SDK vs the fusion, IMU
// position error of the SDK (eq. 16) vs the fusion with the paper's recovery and with the
// smoother, and of the frame results (the frame merge's choice per frame: the strap's position,
// else a recovered gap's where it came before the frame left the merge, else the causal live
// estimate), RMS and maximum over all frames and inside gaps only.
// Two renders:
//   --render body (the simulator's session generator, core/sim/sim_session.hpp, as posefuse-sim
//     makes it: the rendered body with clothing, RGB with the strap, both arms exercising with an
//     IMU each, scored per arm): the protocol with seeds 1 and 2, each clip with seed 3, 4, ...
//     Plots table1_body_<session>_<L|R>.png.
//   --render cylinder (the default; table1/table1_session.hpp: the right forearm IMU, colour and
//     depth of the forearm and upper arm as cylinders): the protocol, paper 1's method and
//     diagnostic variants, each clip. Plots table1_<session>.png.
// Plots: Figs. 4-6, errors and x_K over time, occluded frames grey.
//
//   build/bench/bench_table1 [--render body|cylinder] [--fit] [--live-order] [--protocol-only]
//                            [--protocol-seeds N] [--only NAME] [--option KEY=VALUE]... [--gaps]
//                            [--imu-noise-only]
//                            [mocap folder=../shared/data/mocap]
//                            [image folder=docs/images] [longest clip s=20]
// Body render only: --fit runs the body fit too (fit.enabled = true), so the forearm smoother is
// anchored to the fit's elbows (forearm.gap_anchor = auto) instead of the camera skeleton's.
// --live-order: each session's chunks sent by camera time, as a live recording interleaves them
// (table1/body_render_session.hpp), not in posefuse-sim's order. --protocol-only: the two protocol
// sessions, not the clips. --protocol-seeds N: the protocol with seeds 1 .. N (default 2; the clips
// keep seeds 3, 4, ...). --option KEY=VALUE: a session header option (a stage's, e.g.
// fit.skeleton_start_energy=0), repeatable. --only NAME: the sessions whose name
// contains NAME (each with the seed it has in the whole run). --gaps: per recovered gap, the
// boundary fits and the errors against the truth (table1/gap_report.hpp). --imu-noise-only
// (diagnostic): the IMUs without their bias, scale, misalignment and iron errors (white noise
// only, as the cylinder render's IMUs).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "bench_clock.hpp"
#include "common/error.hpp"
#include "session/pipeline.hpp"
#include "session/stages/body_fit_options.hpp"
#include "session/stages/default_stages.hpp"
#include "session/stages/forearm_options.hpp"
#include "sim/bvh.hpp"
#include "sim/bvh_motion.hpp"
#include "sim/calibration_prefix.hpp"
#include "sim/exercises.hpp"
#include "sim/motion_library.hpp"
#include "table1/body_render_session.hpp"
#include "table1/gap_report.hpp"
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
// paper recovery, smoother, live), all frames and inside gaps.
struct Summary {
  std::string name;
  eval::ErrorSummary orientation[2], position[4], gap_position[4];
};

double hold_bound_s(const sim::BodyMotion& motion, bool end) {
  for (const sim::MotionPhase& p : motion.phases) {
    if (p.name == "calibration_hold") return end ? p.end_s : p.begin_s;
  }
  return 0.0;
}

// Prints one session's Table I (title already printed) and writes its plot.
Summary report(const std::string& name, const bench::Table1Series& s, const fs::path& png) {
  std::printf(
      "| error (frames) | SDK | fusion, paper recovery | fusion, smoother | fusion, frame results | paper 1 SDK -> "
      "fusion |\n");
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
  std::printf("the stage accepted the strap (eq. 10, II-J tests) at %zu of the %zu frames where it is visible\n",
              accepted, truth_visible);
  if (s.sdk_orientation_missing > 0)
    std::printf("(SDK gave no wrist orientation at %zu frames)\n", s.sdk_orientation_missing);

  const cv::Scalar red(40, 40, 220), blue(200, 90, 20), orange(20, 140, 240), black(0, 0, 0);
  const bool written =
      bench::write_time_plot(png.string(), s.t_s, s.occluded,
                             {{"orientation error, deg (eqs. 14-15; Fig. 4)",
                               {{"SDK", s.sdk_orientation_deg, red}, {"fusion", s.fusion_orientation_deg, blue}}},
                              {"IMU position error, m (Fig. 5)",
                               {{"SDK (eq. 16)", s.sdk_position_m, red},
                                {"paper recovery", s.paper_position_m, orange},
                                {"smoother", s.smoother_position_m, blue}}},
                              {"IMU x_K, m (Fig. 6)",
                               {{"truth", s.true_x_m, black},
                                {"SDK (eq. 16)", s.sdk_x_m, red},
                                {"paper recovery", s.paper_x_m, orange},
                                {"smoother", s.smoother_x_m, blue}}}});
  std::printf("plot: %s%s\n", png.string().c_str(), written ? "" : " (NOT written)");
  Summary summary{name, {}, {}, {}};
  for (std::size_t i = 0; i < 2; ++i) summary.orientation[i] = eval::summarize_errors(orientation[i]);
  for (std::size_t i = 0; i < 4; ++i) {
    summary.position[i] = eval::summarize_errors(position[i]);
    summary.gap_position[i] = eval::summarize_errors(position[i], s.occluded);
  }
  return summary;
}

void print_title(const std::string& name, std::uint64_t seed, const bench::Table1Series& s, double hold_begin,
                 double hold_end, double sim_cpu_s, double pipeline_cpu_s) {
  std::size_t occluded = 0;
  for (const bool o : s.occluded) occluded += o;
  std::printf(
      "\n### %s (seed %llu): %.1f s, %zu frames, %zu occluded in %zu gaps; calibration hold %.1f-%.1f s; "
      "CPU s: simulation %.1f, pipeline %.1f\n\n",
      name.c_str(), static_cast<unsigned long long>(seed), s.t_s.back(), s.t_s.size(), occluded, gap_count(s.occluded),
      hold_begin, hold_end, sim_cpu_s, pipeline_cpu_s);
}

Summary run_cylinder(const Named& session_motion, const fs::path& image_folder, double longest_s, std::uint64_t seed) {
  bench::Table1SessionOptions options;
  options.seed = seed;
  options.strap.F_from_A = geometry::quat_from_rotation_vector(geometry::Vec3(0.2, -0.1, 0.3));
  options.duration_s = longest_s;
  options.sdk_joint_errors = session_motion.sdk_joint_errors;
  const double hold_begin = hold_bound_s(session_motion.motion, false),
               hold_end = hold_bound_s(session_motion.motion, true);
  options.calibration_end_s = hold_end;
  const double cpu0 = bench::thread_cpu_seconds();
  const bench::Table1Session session = bench::simulate_table1_session(session_motion.motion, options);
  const double cpu1 = bench::thread_cpu_seconds();
  Sink sink;
  session::SessionPipeline pipeline(session::make_default_stages(), sink);
  bench::Table1Truth truth{session.frame_t_us, session.forearm, {}};
  for (v1::SessionChunk chunk : session.chunks) {
    if (chunk.has_header()) {
      auto& stage_options = *chunk.mutable_header()->mutable_options();
      stage_options[session::kForearmAxisKey] = session_motion.axis;
      stage_options[session::kForearmShoulderSphereKey] = session_motion.shoulder_sphere;
      stage_options[session::kForearmUpperArmKey] = session_motion.upper_arm;
    }
    if (chunk.has_skeleton()) truth.sdk.push_back(chunk.skeleton());
    pipeline.push(chunk);
  }
  pipeline.close();
  const double cpu2 = bench::thread_cpu_seconds();
  for (const v1::FitResult& r : sink.results) {
    if (r.has_warning()) std::printf("warning: %s\n", r.warning().ShortDebugString().c_str());
  }
  const bench::Table1Series s = bench::table1_series(
      truth, sink.results, {v1::RIGHT, "arm_r", options.strap.strap_to_elbow_m, session.d_sw_m}, hold_begin, hold_end);
  print_title(session_motion.name, seed, s, hold_begin, hold_end, cpu1 - cpu0, cpu2 - cpu1);
  return report(session_motion.name, s, image_folder / ("table1_" + session_motion.name + ".png"));
}

std::vector<fs::path> mocap_clips(const fs::path& mocap) {
  std::vector<fs::path> files;
  if (!fs::is_directory(mocap)) {
    std::printf("%s not found: the protocol only\n", mocap.string().c_str());
    return files;
  }
  for (const auto& entry : fs::directory_iterator(mocap)) {
    if (entry.is_regular_file() && entry.path().extension() == ".bvh") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::vector<Summary> cylinder_sessions(const fs::path& mocap, const fs::path& images, double longest_s) {
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
  const sim::BodyMotion calibration = sim::make_exercise("calibration_pose", protocol);
  for (const fs::path& file : mocap_clips(mocap)) {
    try {
      sessions.push_back(
          {file.stem().string(), sim::with_calibration_prefix(calibration, sim::bvh_motion(sim::load_bvh(file)))});
    } catch (const Error& e) {
      std::printf("%s: skipped (%s)\n", file.string().c_str(), e.what());
    }
  }
  std::vector<Summary> summaries;
  std::uint64_t seed = 0;
  for (const Named& s : sessions) {
    // Every session draws its own SDK biases and noise; the variants (paper axis, exact SDK) repeat
    // their predecessor's.
    if (s.sdk_joint_errors && s.axis == "depth" && s.upper_arm == "depth") ++seed;
    try {
      summaries.push_back(run_cylinder(s, images, longest_s, seed));
    } catch (const Error& e) {
      std::printf("\n### %s: failed: %s\n", s.name.c_str(), e.what());
    }
  }
  return summaries;
}

// One posefuse-sim session (both arms exercising, an IMU on each), scored per arm.
// The body render's command-line switches.
struct BodyFlags {
  bool print_gaps = false, imu_noise_only = false, fit = false, protocol_only = false, live_order = false;
  std::string only;                                   // --only: the sessions whose name contains this
  int protocol_seeds = 2;                             // --protocol-seeds: the protocol with seeds 1 .. this
  std::map<std::string, std::string> header_options;  // --option KEY=VALUE (after --fit's)
};

std::vector<Summary> run_body(const std::string& name, const sim::SimSessionOptions& options, const fs::path& images,
                              const BodyFlags& flags) {
  const sim::BodyMotion motion =
      sim::select_motion(options.motion, options.motion_options, {options.sex, options.betas});
  const double hold_begin = hold_bound_s(motion, false), hold_end = hold_bound_s(motion, true);
  std::map<std::string, std::string> header_options;
  if (flags.fit) header_options[session::kFitEnabledKey] = "true";
  for (const auto& [key, value] : flags.header_options) header_options[key] = value;
  const bench::BodyRenderRun run = bench::run_body_render_session(options, header_options, flags.live_order);
  double sim_cpu_s = 0.0;
  for (const auto& [part, seconds] : run.truth.cpu_s) sim_cpu_s += seconds;
  for (const v1::FitResult& r : run.results) {
    if (r.has_warning()) std::printf("warning: %s\n", r.warning().ShortDebugString().c_str());
  }
  std::vector<Summary> summaries;
  for (int arm = 0; arm < 2; ++arm) {
    if (!bench::has_arm(run, arm)) continue;
    const std::string arm_name = name + (arm == 0 ? "_L" : "_R");
    const bench::Table1Series s = bench::table1_series(bench::body_render_truth(run, arm), run.results,
                                                       bench::body_render_arm(run, arm), hold_begin, hold_end);
    print_title(arm_name, options.seed, s, hold_begin, hold_end, sim_cpu_s, run.pipeline_cpu_s);
    if (flags.print_gaps)
      bench::print_gap_report(bench::body_render_truth(run, arm), run.results, bench::body_render_arm(run, arm));
    summaries.push_back(report(arm_name, s, images / ("table1_body_" + arm_name + ".png")));
  }
  return summaries;
}

std::vector<Summary> body_sessions(const fs::path& mocap, const fs::path& images, double longest_s,
                                   const BodyFlags& flags) {
  sim::SimSessionOptions options;
  options.motion = "forearm_protocol";
  options.motion_options.exercise.repetitions = 1;
  options.motion_options.exercise.arm = sim::ExerciseArm::kBoth;
  options.duration_s = longest_s;
  if (flags.imu_noise_only) {
    const sim::ImuErrorModel typical;
    options.imu.synth.error_model = sim::ImuErrorModel::none();
    options.imu.synth.error_model.gyr_noise_density_rad_s_sqrt_hz = typical.gyr_noise_density_rad_s_sqrt_hz;
    options.imu.synth.error_model.acc_noise_density_m_s2_sqrt_hz = typical.acc_noise_density_m_s2_sqrt_hz;
    options.imu.synth.error_model.mag_noise_uT = typical.mag_noise_uT;
  }
  std::vector<Summary> summaries;
  const auto add = [&](const std::string& name) {
    if (name.find(flags.only) == std::string::npos) return;  // seeds stay those of the whole run
    try {
      for (Summary& s : run_body(name, options, images, flags)) summaries.push_back(std::move(s));
    } catch (const Error& e) {
      std::printf("\n### %s: failed: %s\n", name.c_str(), e.what());
    }
  };
  for (int seed = 1; seed <= flags.protocol_seeds; ++seed) {
    options.seed = static_cast<std::uint64_t>(seed);
    add("protocol_seed" + std::to_string(seed));
  }
  if (flags.protocol_only) return summaries;
  options.seed = 2;  // the clips keep seeds 3, 4, ... whatever the number of protocol seeds
  options.motion = "bvh";
  options.motion_options.calibration_prefix = true;
  for (const fs::path& file : mocap_clips(mocap)) {
    ++options.seed;
    options.motion_options.bvh_path = file.string();
    try {
      const double clip_s = sim::select_motion("bvh", options.motion_options, {options.sex, options.betas}).duration_s;
      options.duration_s = std::min(longest_s, clip_s);
    } catch (const Error& e) {
      std::printf("%s: skipped (%s)\n", file.string().c_str(), e.what());
      continue;
    }
    add(file.stem().string());
  }
  return summaries;
}

// The protocol's arms together against the targets: how many arms meet each, and the errors
// pooled over all their frames (RMS over every frame, the largest maximum).
void print_protocol_pool(const std::vector<Summary>& summaries) {
  struct Pool {
    double sum_sq = 0.0, max = 0.0;
    std::size_t count = 0;
    int arms_meeting = 0;
    void add(const eval::ErrorSummary& e, bool meets) {
      sum_sq += e.rms * e.rms * static_cast<double>(e.count);
      count += e.count;
      max = std::max(max, e.max);
      arms_meeting += meets ? 1 : 0;
    }
    double rms() const { return count > 0 ? std::sqrt(sum_sq / static_cast<double>(count)) : 0.0; }
  };
  Pool orientation, smoother;
  int arms = 0, smoother_max_meeting = 0;
  for (const Summary& u : summaries) {
    if (!u.name.starts_with("protocol_")) continue;
    ++arms;
    orientation.add(u.orientation[1], u.orientation[1].rms <= 5.0);
    smoother.add(u.position[2], u.position[2].rms <= 0.02);
    smoother_max_meeting += u.position[2].max <= 0.06 ? 1 : 0;
  }
  if (arms == 0) return;
  std::printf(
      "\nprotocol, %d arms pooled: orientation RMS %.2f deg (max %.2f; %d of %d arms <= 5 deg), smoother "
      "position RMS %.4f m (max %.4f; %d of %d arms <= 0.02 m RMS, %d of %d <= 0.06 m max)\n",
      arms, orientation.rms(), orientation.max, orientation.arms_meeting, arms, smoother.rms(), smoother.max,
      smoother.arms_meeting, arms, smoother_max_meeting, arms);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  std::string render = "cylinder";
  BodyFlags flags;
  const std::map<std::string, bool BodyFlags::*> switches = {{"--gaps", &BodyFlags::print_gaps},
                                                             {"--imu-noise-only", &BodyFlags::imu_noise_only},
                                                             {"--fit", &BodyFlags::fit},
                                                             {"--protocol-only", &BodyFlags::protocol_only},
                                                             {"--live-order", &BodyFlags::live_order}};
  while (!args.empty() && args[0].starts_with("--")) {
    if (const auto it = switches.find(args[0]); it != switches.end()) {
      flags.*(it->second) = true;
      args.erase(args.begin());
    } else if (args[0] == "--only" && args.size() >= 2) {
      flags.only = args[1];
      args.erase(args.begin(), args.begin() + 2);
    } else if (args[0] == "--option" && args.size() >= 2) {
      const std::size_t equals = args[1].find('=');
      if (equals == std::string::npos || equals == 0) {
        std::fprintf(stderr, "bench_table1: --option needs KEY=VALUE, not '%s'\n", args[1].c_str());
        return 2;
      }
      flags.header_options[args[1].substr(0, equals)] = args[1].substr(equals + 1);
      args.erase(args.begin(), args.begin() + 2);
    } else if (args[0] == "--protocol-seeds" && args.size() >= 2) {
      try {
        flags.protocol_seeds = std::stoi(args[1]);
      } catch (const std::exception&) {
        flags.protocol_seeds = 0;
      }
      if (flags.protocol_seeds < 1 || flags.protocol_seeds > 100) {
        std::fprintf(stderr, "bench_table1: --protocol-seeds must be a whole number from 1 to 100, not '%s'\n",
                     args[1].c_str());
        return 2;
      }
      args.erase(args.begin(), args.begin() + 2);
    } else if (args[0] == "--render" && args.size() >= 2) {
      render = args[1];
      args.erase(args.begin(), args.begin() + 2);
    } else {
      std::fprintf(stderr, "bench_table1: unknown option '%s'\n", args[0].c_str());
      return 2;
    }
  }
  if (render != "cylinder" && render != "body") {
    std::fprintf(stderr, "bench_table1: --render must be body or cylinder, not '%s'\n", render.c_str());
    return 2;
  }
  const fs::path mocap = args.size() > 0 ? fs::path(args[0]) : fs::path("../shared/data/mocap");
  const fs::path images = args.size() > 1 ? fs::path(args[1]) : fs::path("docs/images");
  const double longest_s = args.size() > 2 ? std::stod(args[2]) : 20.0;
  if (render != "body" &&
      (flags.fit || flags.live_order || flags.protocol_only || flags.print_gaps || flags.imu_noise_only ||
       !flags.only.empty() || flags.protocol_seeds != 2 || !flags.header_options.empty())) {
    std::fprintf(stderr,
                 "bench_table1: --fit, --live-order, --protocol-only, --protocol-seeds, --only, --option, --gaps "
                 "and --imu-noise-only need --render body\n");
    return 2;
  }
  std::printf("paper 1 Table I on simulated sessions, %s render%s; sessions cut at %.0f s\n", render.c_str(),
              flags.fit ? " with the body fit (the smoother anchored to the fit's elbows)" : "", longest_s);
  const double cpu0 = bench::thread_cpu_seconds();
  const std::vector<Summary> summaries =
      render == "body" ? body_sessions(mocap, images, longest_s, flags) : cylinder_sessions(mocap, images, longest_s);
  std::printf(
      "\n### summary (%s render; all frames, and inside gaps; targets on the protocol: orientation RMS <= 5 "
      "deg, smoother position RMS <= 0.02 m and max <= 0.06 m)\n\n",
      render.c_str());
  std::printf(
      "| session | orient. RMS deg SDK / fusion | orient. max deg SDK / fusion | position RMS m SDK / paper / "
      "smoother / live | position max m SDK / paper / smoother / live | in gaps: position RMS m SDK / paper / "
      "smoother / live | in gaps: position max m SDK / paper / smoother / live |\n|---|---|---|---|---|---|---|\n");
  std::printf("| paper 1 | 84.25 / 11.34 | 179.79 / 17.43 | 0.0703 / 0.0407 / - / - | 0.2392 / 0.1410 / - / - | | |\n");
  for (const Summary& u : summaries) {
    std::printf("| %s | %.2f / %.2f | %.2f / %.2f |", u.name.c_str(), u.orientation[0].rms, u.orientation[1].rms,
                u.orientation[0].max, u.orientation[1].max);
    for (const eval::ErrorSummary* p : {u.position, u.gap_position}) {
      std::printf(" %.4f / %.4f / %.4f / %.4f | %.4f / %.4f / %.4f / %.4f |", p[0].rms, p[1].rms, p[2].rms, p[3].rms,
                  p[0].max, p[1].max, p[2].max, p[3].max);
    }
    std::printf("\n");
  }
  print_protocol_pool(summaries);
  std::printf("\nCPU s, this thread: %.1f (the body render's frame workers are counted in 'simulation' per session)\n",
              bench::thread_cpu_seconds() - cpu0);
  return 0;
}
