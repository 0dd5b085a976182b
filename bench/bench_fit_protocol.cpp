// The body-model fit on a posefuse-sim session, by phase of the motion (issue 7: paper 1's protocol,
// where the forearms hide behind the head and the back):
//
//   build/bench/bench_fit_protocol SIM_OPTIONS SESSION.pfchunks GT_DIR OUT_DIR [--option KEY=VALUE]...
//                                  [--frames-csv PATH] [--score-existing]
//
// SIM_OPTIONS is the options file posefuse-sim made SESSION and GT_DIR from (it gives the motion's
// phases); the session goes through SessionPipeline(make_default_stages()) with fit.enabled=true
// (and the given header options), the results are written to OUT_DIR as the client writes them
// (posefuse-score OUT_DIR GT_DIR scores them). Printed per phase: frames, lost frames (energy above
// fit.lost_energy), the mean error of the fit's SMPL shoulders, elbows and wrists and of the camera
// skeleton's, the forearm stage's IMU position error (VISUAL / PREDICTED) and the fit's point at the
// strap (the true d_se along the fitted forearm against the same point on the true forearm: the
// truth only scores here). A frame belongs to the phase whose hold it is in or moves towards;
// frames after the last hold are "rest". --frames-csv writes every frame's numbers.
// --score-existing: OUT_DIR already holds the results of a run (e.g. `bench_sim_forearm replay ...
// --option fit.enabled=true` built from another commit); the pipeline is not run, and the energies
// and lost frames, which the result files do not hold, are printed as nan and -1.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_clock.hpp"
#include "body/smpl_model.hpp"
#include "client/result_writer.hpp"
#include "session/chunk_file.hpp"
#include "session/pipeline.hpp"
#include "session/result_reader.hpp"
#include "session/stages/body_fit_options.hpp"
#include "session/stages/body_fit_stage.hpp"
#include "session/stages/default_stages.hpp"
#include "sim/motion_library.hpp"
#include "tools/sim/sim_options_file.hpp"

namespace {

using namespace posefuse;
namespace fs = std::filesystem;
using Vec3 = Eigen::Vector3d;

constexpr int kSides = 2;  // left, right
constexpr int kKinds = 3;  // shoulder, elbow, wrist
const int kSmpl[kKinds][kSides] = {{body::kLeftShoulder, body::kRightShoulder},
                                   {body::kLeftElbow, body::kRightElbow},
                                   {body::kLeftWrist, body::kRightWrist}};
const int kCamera[kKinds][kSides] = {{4, 8}, {5, 9}, {6, 10}};  // Kinect v2 ShoulderLeft.. WristRight
const char* const kDevice[kSides] = {"imu_left", "imu_right"};

Vec3 vec(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }

// Writes everything the pipeline emits (as the client does) and keeps the frame results.
struct Sink : session::ResultSink {
  explicit Sink(client::ResultWriter& w) : writer(w) {}
  void emit(v1::FitResult&& result) override {
    if (result.has_frame()) {
      const v1::FrameResult& f = result.frame();
      if (f.smpl_joints_size() == body::kNumJoints) fit[f.t_us()] = f;
      for (const auto& p : f.imu_positions()) imu[{f.t_us(), p.device_id()}] = p;
    }
    if (result.has_warning()) {
      std::printf("warning %s %s: %s\n", result.warning().code().c_str(), result.warning().field().c_str(),
                  result.warning().message().c_str());
    }
    writer.write(result);
  }
  client::ResultWriter& writer;
  std::map<std::int64_t, v1::FrameResult> fit;
  std::map<std::pair<std::int64_t, std::string>, v1::ImuPosition> imu;
};

struct Truth {
  std::map<std::int64_t, std::map<int, Vec3>> smpl, camera;
  std::map<std::pair<std::int64_t, std::string>, Vec3> imu;
  double d_se_m[kSides] = {0.15, 0.15};
};

Truth read_truth(const fs::path& gt) {
  const session::ResultDirectory d = session::read_result_files(gt);
  Truth t;
  for (const auto& j : d.smpl_joints) t.smpl[j.t_us][j.joint] = j.p_K;
  for (const auto& j : d.camera_joints) t.camera[j.t_us][j.joint] = j.p_K;
  for (const auto& p : d.imu_positions) t.imu[{p.t_us, p.device_id}] = p.p_K;
  if (d.calibration) {
    for (const auto& m : d.calibration->forearms()) t.d_se_m[m.arm() == v1::LEFT ? 0 : 1] = m.d_se_m();
  }
  return t;
}

struct Mean {
  double sum = 0;
  int n = 0;
  void add(double v) {
    if (!std::isfinite(v)) return;
    sum += v;
    ++n;
  }
  double value() const { return n ? sum / n : NAN; }
};

struct PhaseSums {
  int frames = 0, lost = 0;
  Mean fit[kKinds][kSides], camera[kKinds][kSides];
  Mean fit_strap[kSides], visual[kSides], predicted[kSides];
  int visual_n[kSides] = {0, 0}, predicted_n[kSides] = {0, 0};
  std::vector<double> energy;
};

// The phase of time t: the hold it is in or the next one (the move towards it); "rest" after the last.
std::string phase_at(const std::vector<sim::MotionPhase>& phases, double t_s) {
  for (const auto& p : phases)
    if (t_s <= p.end_s) return p.name;
  return "rest";
}

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// The frame results and IMU positions of a result directory written earlier (no fit energies).
void read_existing(const fs::path& dir, Sink& sink) {
  const session::ResultDirectory d = session::read_result_files(dir);
  for (const auto& j : d.smpl_joints) {
    v1::FrameResult& f = sink.fit[j.t_us];
    f.set_t_us(j.t_us);
    f.set_fit_energy(NAN);
    while (f.smpl_joints_size() <= j.joint) f.add_smpl_joints();
    v1::Vec3& p = *f.mutable_smpl_joints(j.joint)->mutable_position_m();
    p.set_x(j.p_K.x());
    p.set_y(j.p_K.y());
    p.set_z(j.p_K.z());
  }
  for (const auto& row : d.imu_positions) {
    v1::ImuPosition& p = sink.imu[{row.t_us, row.device_id}];
    p.set_device_id(row.device_id);
    p.mutable_position_m()->set_x(row.p_K.x());
    p.mutable_position_m()->set_y(row.p_K.y());
    p.mutable_position_m()->set_z(row.p_K.z());
    p.set_source(row.source);
  }
}

int run(const fs::path& sim_options_path, const fs::path& chunks, const fs::path& gt, const fs::path& out,
        const std::vector<std::string>& options, const std::string& frames_csv, bool score_existing) {
  sim::SimSessionOptions sim_options;
  tools::apply_sim_options_file(sim_options_path, sim_options);
  const sim::BodyMotion motion =
      sim::select_motion(sim_options.motion, sim_options.motion_options, {sim_options.sex, sim_options.betas});
  const Truth truth = read_truth(gt);

  double lost_energy = 100.0;
  std::map<std::int64_t, v1::SkeletonFrame> skeletons;
  std::vector<session::BodyFitFrameStats> stats;
  const double cpu0 = bench::thread_cpu_seconds();
  const auto wall0 = bench::WallClock::now();
  if (!score_existing) fs::remove_all(out);
  client::ResultWriter writer(score_existing ? fs::temp_directory_path() / "bench_fit_protocol_unused" : out);
  Sink sink(writer);
  if (score_existing) {
    read_existing(out, sink);
    session::ChunkFileReader reader(chunks);
    v1::SessionChunk chunk;
    std::optional<std::uint32_t> body;
    while (reader.next(chunk)) {
      if (!chunk.has_skeleton()) continue;
      if (!body) body = chunk.skeleton().body_id();
      if (chunk.skeleton().body_id() == *body) skeletons[chunk.skeleton().t_us()] = chunk.skeleton();
    }
  } else {
    std::vector<std::unique_ptr<session::Stage>> stages = session::make_default_stages();
    session::BodyFitStage* fit_stage = nullptr;
    for (auto& s : stages)
      if (auto* b = dynamic_cast<session::BodyFitStage*>(s.get())) fit_stage = b;
    if (!fit_stage) throw std::runtime_error("no body_fit stage in make_default_stages()");
    fit_stage->record_frame_stats(true);
    session::SessionPipeline pipeline(std::move(stages), sink);
    session::ChunkFileReader reader(chunks);
    v1::SessionChunk chunk;
    std::optional<std::uint32_t> body;
    while (reader.next(chunk)) {
      if (chunk.has_header()) {
        auto& header_options = *chunk.mutable_header()->mutable_options();
        header_options[session::kFitEnabledKey] = "true";
        for (const std::string& kv : options) {
          const auto eq = kv.find('=');
          if (eq == std::string::npos) throw std::invalid_argument("--option '" + kv + "': expected KEY=VALUE");
          header_options[kv.substr(0, eq)] = kv.substr(eq + 1);
        }
        if (header_options.count(session::kFitLostEnergyKey)) {
          lost_energy = std::stod(header_options[session::kFitLostEnergyKey]);
        }
      }
      if (chunk.has_skeleton()) {
        if (!body) body = chunk.skeleton().body_id();
        if (chunk.skeleton().body_id() == *body) skeletons[chunk.skeleton().t_us()] = chunk.skeleton();
      }
      pipeline.push(chunk);
    }
    pipeline.close();
    stats = fit_stage->frame_stats();
  }
  writer.finish();
  const double cpu_s = bench::thread_cpu_seconds() - cpu0, wall_s = 1e-3 * bench::wall_ms_since(wall0);
  std::map<std::int64_t, const session::BodyFitFrameStats*> stats_at;
  for (const auto& s : stats) stats_at[s.t_us] = &s;

  std::FILE* csv = frames_csv.empty() ? nullptr : std::fopen(frames_csv.c_str(), "w");
  if (csv) {
    std::fprintf(csv, "t_s,phase,energy,lost,previous_won,it_previous,it_skeleton,E_previous,E_skeleton");
    for (const char* who : {"fit", "cam"})
      for (const char* side : {"L", "R"})
        for (const char* kind : {"sh", "el", "wr"}) std::fprintf(csv, ",%s_%s%s", who, side, kind);
    std::fprintf(csv, ",fit_strap_L,fit_strap_R,imu_L,imu_src_L,imu_R,imu_src_R\n");
  }
  std::vector<std::string> order;
  std::map<std::string, PhaseSums> sums;
  PhaseSums all;
  for (const auto& [t_us, frame] : sink.fit) {
    const auto ts = truth.smpl.find(t_us);
    const auto tc = truth.camera.find(t_us);
    const auto sk = skeletons.find(t_us);
    if (ts == truth.smpl.end()) continue;
    const std::string phase = phase_at(motion.phases, 1e-6 * static_cast<double>(t_us));
    if (!sums.count(phase)) order.push_back(phase);
    PhaseSums& p = sums[phase];
    const auto st = stats_at.find(t_us);
    const double energy = frame.fit_energy();
    const bool lost = energy > lost_energy;  // false for a NaN energy (--score-existing)
    double fit_e[kKinds][kSides], cam_e[kKinds][kSides], strap_e[kSides], imu_e[kSides];
    std::string imu_src[kSides];
    for (int s = 0; s < kSides; ++s) {
      for (int k = 0; k < kKinds; ++k) {
        fit_e[k][s] = (vec(frame.smpl_joints(kSmpl[k][s]).position_m()) - ts->second.at(kSmpl[k][s])).norm();
        cam_e[k][s] = NAN;
        if (tc != truth.camera.end() && sk != skeletons.end())
          cam_e[k][s] = (vec(sk->second.joints(kCamera[k][s]).position_m()) - tc->second.at(kCamera[k][s])).norm();
      }
      // The strap's point on the forearm axis, fitted against true.
      const auto axis_point = [&](const Vec3& elbow, const Vec3& wrist) {
        return Vec3(elbow + truth.d_se_m[s] * (wrist - elbow).normalized());
      };
      strap_e[s] = (axis_point(vec(frame.smpl_joints(kSmpl[1][s]).position_m()),
                               vec(frame.smpl_joints(kSmpl[2][s]).position_m())) -
                    axis_point(ts->second.at(kSmpl[1][s]), ts->second.at(kSmpl[2][s])))
                       .norm();
      imu_e[s] = NAN;
      const auto ip = sink.imu.find({t_us, kDevice[s]});
      const auto it = truth.imu.find({t_us, kDevice[s]});
      if (ip != sink.imu.end() && it != truth.imu.end()) {
        imu_e[s] = (vec(ip->second.position_m()) - it->second).norm();
        imu_src[s] = v1::Source_Name(ip->second.source());
      }
    }
    for (PhaseSums* q : {&p, &all}) {
      ++q->frames;
      q->lost += lost;
      q->energy.push_back(energy);
      for (int s = 0; s < kSides; ++s) {
        for (int k = 0; k < kKinds; ++k) {
          q->fit[k][s].add(fit_e[k][s]);
          q->camera[k][s].add(cam_e[k][s]);
        }
        q->fit_strap[s].add(strap_e[s]);
        if (imu_src[s] == "VISUAL") {
          q->visual[s].add(imu_e[s]);
          ++q->visual_n[s];
        } else if (imu_src[s] == "PREDICTED") {
          q->predicted[s].add(imu_e[s]);
          ++q->predicted_n[s];
        }
      }
    }
    if (csv) {
      std::fprintf(csv, "%.4f,%s,%.4g,%d,%d,%d,%d,%.4g,%.4g", 1e-6 * static_cast<double>(t_us), phase.c_str(), energy,
                   lost ? 1 : 0, st != stats_at.end() && st->second->previous_won ? 1 : 0,
                   st != stats_at.end() ? st->second->iterations_previous : -1,
                   st != stats_at.end() ? st->second->iterations_skeleton : -1,
                   st != stats_at.end() ? st->second->energy_previous : NAN,
                   st != stats_at.end() ? st->second->energy_skeleton : NAN);
      for (const auto* e : {&fit_e, &cam_e})
        for (int s = 0; s < kSides; ++s)
          for (int k = 0; k < kKinds; ++k) std::fprintf(csv, ",%.4f", (*e)[k][s]);
      std::fprintf(csv, ",%.4f,%.4f,%.4f,%s,%.4f,%s\n", strap_e[0], strap_e[1], imu_e[0], imu_src[0].c_str(), imu_e[1],
                   imu_src[1].c_str());
    }
  }
  if (csv) std::fclose(csv);

  std::printf("\nphases of %s (s):", sim_options.motion.c_str());
  for (const auto& p : motion.phases) std::printf(" %s %.2f-%.2f;", p.name.c_str(), p.begin_s, p.end_s);
  std::printf(
      "\n\nArm joint error by phase, mm (mean; left / right). fit = SMPL joints of the body fit, camera = "
      "the session's camera skeleton;\nstrap = the fit's forearm point at d_se; IMU = the forearm stage's IMU "
      "position (frames VISUAL, PREDICTED)\n");
  std::printf(
      "| phase | frames | lost | E median | fit shoulders | fit elbows | fit wrists | fit all six | camera "
      "elbows | camera wrists | camera all six | fit strap point | IMU VISUAL | IMU PREDICTED |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  const auto row = [&](const std::string& name, const PhaseSums& p) {
    const auto lr = [](const Mean(&m)[kSides]) {
      char b[64];
      std::snprintf(b, sizeof b, "%.0f / %.0f", 1e3 * m[0].value(), 1e3 * m[1].value());
      return std::string(b);
    };
    const auto six = [](const Mean(&m)[kKinds][kSides]) {
      Mean all6;
      for (int k = 0; k < kKinds; ++k)
        for (int s = 0; s < kSides; ++s) {
          all6.sum += m[k][s].sum;
          all6.n += m[k][s].n;
        }
      return 1e3 * all6.value();
    };
    char visual[64], predicted[64];
    std::snprintf(visual, sizeof visual, "%.0f (%d) / %.0f (%d)", 1e3 * p.visual[0].value(), p.visual_n[0],
                  1e3 * p.visual[1].value(), p.visual_n[1]);
    std::snprintf(predicted, sizeof predicted, "%.0f (%d) / %.0f (%d)", 1e3 * p.predicted[0].value(), p.predicted_n[0],
                  1e3 * p.predicted[1].value(), p.predicted_n[1]);
    std::printf("| %s | %d | %d | %.1f | %s | %s | %s | %.1f | %s | %s | %.1f | %s | %s | %s |\n", name.c_str(),
                p.frames, score_existing ? -1 : p.lost, median(p.energy), lr(p.fit[0]).c_str(), lr(p.fit[1]).c_str(),
                lr(p.fit[2]).c_str(), six(p.fit), lr(p.camera[1]).c_str(), lr(p.camera[2]).c_str(), six(p.camera),
                lr(p.fit_strap).c_str(), visual, predicted);
  };
  for (const auto& name : order) row(name, sums[name]);
  row("all", all);
  std::printf("\npipeline: %.2f s CPU (this thread), %.2f s wall\n", cpu_s, wall_s);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    std::vector<std::string> positional, options;
    std::string frames_csv;
    bool score_existing = false;
    for (int a = 1; a < argc; ++a) {
      const std::string arg = argv[a];
      if (arg == "--option" && a + 1 < argc) {
        options.push_back(argv[++a]);
      } else if (arg == "--score-existing") {
        score_existing = true;
      } else if (arg == "--frames-csv" && a + 1 < argc) {
        frames_csv = argv[++a];
      } else {
        positional.push_back(arg);
      }
    }
    if (positional.size() != 4) {
      std::fprintf(stderr,
                   "usage: bench_fit_protocol SIM_OPTIONS SESSION.pfchunks GT_DIR OUT_DIR [--option KEY=VALUE]... "
                   "[--frames-csv PATH] [--score-existing]\n");
      return 2;
    }
    return run(positional[0], positional[1], positional[2], positional[3], options, frames_csv, score_existing);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_fit_protocol: %s\n", e.what());
    return 1;
  }
}
