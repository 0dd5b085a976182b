// Paper 2, Fig. 4 on simulated sessions (issue 7 "Measured"): mean position error of shoulders,
// elbows and wrists for the camera skeleton, the body-model fit (BodyFitStage, with the imu term)
// and the fit without the imu term, over all frames and over the frames where a forearm is
// occluded; the shoulder elevation error on the shoulder-lift exercise; time per frame.
//
// Sessions: the six exercises of paper 2 (IV-B, core/sim/exercises.hpp), each preceded by 1 s of
// the controlled pose (arms 45 deg from the trunk) for the personalisation, rendered by
// simulate_camera_session with its depth noise and camera-skeleton error model, subsampled to
// `rate_hz` frames per second (default 5) to keep the run short. Model mismatch: the subject's
// shape differs from the template (betas drawn per exercise); the simulator has no clothing or
// soft-tissue mismatch yet. IMU: the wrist IMUs are not simulated here; the forearm orientation
// K_from_F the forearm stage would give is the truth turned by a random 3 deg rotation per frame
// (paper 1's filter + calibration error scale), fed to the stage as ForearmOrientationBatches.
//
// Usage: bench_fig4 [options] [rate_hz] [overlay.png] [mocap folder: adds the first 10 s of
// wipe.bvh and box-1.bvh, retargeted by sim::bvh_motion; their first second is overridden by the
// controlled pose]. Options: --no-fine-shape (rough shape only, fit.fine_shape = false),
// --exercises=a,b (a subset of the six), --max-seconds=S (each exercise cut after S seconds, for
// full-rate runs), --lambda-imu=X (the imu term's weight, fit.lambda_imu), --seed-base=K (K > 0:
// other subjects, renders and IMU errors than the default K = 0, e.g. reporting seeds apart from
// tuning ones), --subjects=N (each exercise N times, seed bases K to K + N - 1).
// Environment: FIT_SKELETON_START_ENERGY sets the stage's fit.skeleton_start_energy (II-G start
// policy; 0 = both starts on two threads); FIG4_STATS_CSV=path writes the per-frame phase times;
// FIG4_OPTIONS="key=value,..." sets further stage options (fit.freeze_contour_after, fit.start_velocity_gain).
// Times are thread CPU time of the stage's work per frame (preprocessing, LM fits,
// post-processing), summed over the threads that did it, and the calling thread's alone.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <numbers>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "bench_clock.hpp"
#include "body/pose_parameters.hpp"
#include "body/template_generator.hpp"
#include "fit/joint_kinematics.hpp"
#include "forearm/orientation_uncertainty.hpp"
#include "session/frame_merge.hpp"
#include "session/image_codec.hpp"
#include "session/result_encoder.hpp"
#include "session/stage_inputs.hpp"
#include "session/stages/body_fit_options.hpp"
#include "session/stages/body_fit_stage.hpp"
#include "sim/bvh.hpp"
#include "sim/bvh_motion.hpp"
#include "sim/camera_session.hpp"
#include "sim/exercises.hpp"

using namespace posefuse;

namespace {

constexpr double kDeg = std::numbers::pi / 180;
constexpr double kCalibrationS = 1.0;
constexpr int kKinds = 3;  // shoulders, elbows, wrists
const char* const kKindNames[kKinds] = {"shoulders", "elbows", "wrists"};
// SMPL and camera joints of each kind, left then right.
const int kSmplJoints[kKinds][2] = {{body::kLeftShoulder, body::kRightShoulder},
                                    {body::kLeftElbow, body::kRightElbow},
                                    {body::kLeftWrist, body::kRightWrist}};
const int kCameraJoints[kKinds][2] = {{4, 8}, {5, 9}, {6, 10}};

struct Output : session::StageOutput {
  void emit(v1::FitResult&& result) override {
    if (result.has_frame()) frames[result.frame().t_us()] = result.frame();
  }
  // The fitted frames, as the client receives them from the frame merge.
  void hand_on(session::StageValue&& value) override {
    if (const auto* fitted = std::get_if<session::FittedFrame>(&value)) {
      if (auto result = session::encode_value(session::merge_fit_only(*fitted))) emit(std::move(*result));
    }
  }
  void warn(const std::string& code, const std::string& field, const std::string& message) override {
    std::fprintf(stderr, "  warning %s %s: %s\n", code.c_str(), field.c_str(), message.c_str());
  }
  v1::CalibrationReport& calibration() override { return report; }
  std::map<std::int64_t, v1::FrameResult> frames;
  v1::CalibrationReport report;
};

struct Sums {
  double error[kKinds] = {0, 0, 0};
  int count[kKinds] = {0, 0, 0};
  void add(int kind, double e) {
    error[kind] += e;
    ++count[kind];
  }
  double mean(int kind) const { return count[kind] ? error[kind] / count[kind] : NAN; }
  double mean_all() const {
    const int n = count[0] + count[1] + count[2];
    return n ? (error[0] + error[1] + error[2]) / n : NAN;
  }
};

struct Table {
  Sums camera, fit, fit_no_imu;  // all frames
  Sums camera_occ, fit_occ, fit_no_imu_occ;
  std::vector<double> frame_s;                    // calling thread's CPU time per skeleton chunk (the first measure)
  std::vector<session::BodyFitFrameStats> stats;  // the stage's per-frame phases (all threads)
  // Relative arm length errors (fitted / true - 1; upper arm, forearm, whole arm; left, right): the fitted shape where
  // the personalisation ran, the template where it was refused, the template where it ran.
  std::vector<double> segments_personalised, segments_refused, segments_template_where_personalised;
  double elevation_fit = 0, elevation_camera = 0, elevation_fit_signed = 0;
  int elevation_n = 0;
  int frames = 0, occluded = 0;
};

Eigen::Vector3d vec(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }

Eigen::Quaterniond random_turn(std::mt19937_64& rng, double angle_rad) {
  std::normal_distribution<double> normal;
  const Eigen::Vector3d axis = Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle_rad, axis));
}

// Forearm orientations as the forearm stage would hand them on: one batch per arm, one sample per frame.
std::vector<session::ForearmOrientations> forearm_batches(const sim::CameraSessionResult& sim, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<session::ForearmOrientations> out(2);
  for (int a = 0; a < 2; ++a) {
    session::ForearmOrientations& batch = out[static_cast<size_t>(a)];
    batch.arm = a == 0 ? v1::RIGHT : v1::LEFT;  // straps: right, left
    for (size_t i = 0; i < sim.truth.size(); ++i) {
      batch.t_us.push_back(sim.t_us[i]);
      batch.K_from_F.push_back(random_turn(rng, 3 * kDeg) * sim.truth[i].forearms[static_cast<size_t>(a)].K_from_F);
      batch.pronation_rad.push_back(0.0);
      batch.orientation_rms_rad.push_back(3 * kDeg);  // the turn's size: confident, as a calibrated arm's
      batch.axis_rms_rad.push_back(forearm::kDirectionRmsOverOrientationRms * 3 * kDeg);
    }
  }
  return out;
}

bool g_fine_shape = true;
std::string g_lambda_imu;  // empty: the stage's default

Output run_stage(const sim::CameraSessionResult& sim, const std::vector<session::ForearmOrientations>& batches,
                 std::vector<double>* frame_s, std::vector<session::BodyFitFrameStats>* stats) {
  v1::SessionHeader header = sim.header;
  (*header.mutable_options())[session::kFitEnabledKey] = "true";
  (*header.mutable_options())[session::kFitFineShapeKey] = g_fine_shape ? "true" : "false";
  if (!g_lambda_imu.empty()) (*header.mutable_options())[session::kFitLambdaImuKey] = g_lambda_imu;
  (*header.mutable_options())[session::kFitCalibrationSKey] = std::to_string(kCalibrationS);
  if (const char* energy = std::getenv("FIT_SKELETON_START_ENERGY"))
    (*header.mutable_options())[session::kFitSkeletonStartEnergyKey] = energy;
  // FIG4_OPTIONS="fit.a=1,fit.b=2": further stage options (e.g. fit.freeze_contour_after=0).
  if (const char* extra = std::getenv("FIG4_OPTIONS")) {
    std::string list = extra;
    for (size_t begin = 0; begin < list.size();) {
      const size_t end = std::min(list.find(',', begin), list.size());
      const std::string item = list.substr(begin, end - begin);
      const size_t eq = item.find('=');
      if (eq != std::string::npos) (*header.mutable_options())[item.substr(0, eq)] = item.substr(eq + 1);
      begin = end + 1;
    }
  }
  std::vector<v1::SessionChunk> chunks(1);
  *chunks[0].mutable_header() = header;
  chunks.insert(chunks.end(), sim.chunks.begin(), sim.chunks.end());
  const session::AssembledSession inputs = session::assemble_session(chunks);  // decoded once, not timed
  Output out;
  session::BodyFitStage stage;
  stage.record_frame_stats(stats != nullptr);
  stage.start(header, out);
  for (const auto& b : batches) stage.on_value(b, out);
  for (const session::SessionInput& input : inputs.inputs) {
    const auto* frame = std::get_if<session::CameraFrame>(&input);
    const bool timed = frame && static_cast<double>(frame->t_us) * 1e-6 > kCalibrationS + 0.01;
    const double t0 = bench::thread_cpu_seconds();
    session::deliver_input(stage, input, out);
    if (timed && frame_s) frame_s->push_back(bench::thread_cpu_seconds() - t0);
  }
  stage.finish(out);
  if (stats) {
    for (const auto& f : stage.frame_stats())
      if (static_cast<double>(f.t_us) * 1e-6 > kCalibrationS + 0.01) stats->push_back(f);
  }
  return out;
}

// Elevation of the shoulder above the line across the trunk: angle of neck -> shoulder against
// the plane perpendicular to pelvis -> neck, degrees.
double elevation_deg(const Eigen::Vector3d& pelvis, const Eigen::Vector3d& neck, const Eigen::Vector3d& shoulder) {
  const Eigen::Vector3d up = (neck - pelvis).normalized();
  const Eigen::Vector3d d = (shoulder - neck).normalized();
  return std::asin(std::clamp(d.dot(up), -1.0, 1.0)) / kDeg;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(p * static_cast<double>(v.size())))];
}

// The stage's CPU time per frame by phase (thread CPU of whichever thread did the work, summed).
void print_phases(const std::vector<session::BodyFitFrameStats>& stats) {
  using Stats = session::BodyFitFrameStats;
  const std::vector<std::pair<const char*, double (*)(const Stats&)>> phases = {
      {"assemble frame", [](const Stats& f) { return f.assemble_s; }},
      {"silhouette cleanup", [](const Stats& f) { return f.cleanup_s; }},
      {"point cloud", [](const Stats& f) { return f.observation.cloud_s; }},
      {"zone sampling", [](const Stats& f) { return f.observation.sampling_s; }},
      {"sample normals", [](const Stats& f) { return f.observation.normals_s; }},
      {"D_2D", [](const Stats& f) { return f.observation.d2d_s; }},
      {"D_3D construction", [](const Stats& f) { return f.observation.d3d_s; }},
      {"skeleton start pose", [](const Stats& f) { return f.start_pose_s; }},
      {"LM from previous frame", [](const Stats& f) { return f.fit_previous_s; }},
      {"LM from skeleton pose", [](const Stats& f) { return f.fit_skeleton_s; }},
      {"post-processing", [](const Stats& f) { return f.post_s; }},
      {"total (all threads)", [](const Stats& f) { return f.total_s(); }},
  };
  std::printf("\nstage CPU per frame by phase (%zu frames; ms)\n", stats.size());
  std::printf("| phase | median | mean | p95 |\n|---|---|---|---|\n");
  for (const auto& [name, get] : phases) {
    std::vector<double> v;
    double sum = 0;
    for (const Stats& f : stats) {
      v.push_back(get(f));
      sum += v.back();
    }
    std::printf("| %s | %.2f | %.2f | %.2f |\n", name, 1e3 * percentile(v, 0.5),
                v.empty() ? NAN : 1e3 * sum / static_cast<double>(v.size()), 1e3 * percentile(v, 0.95));
  }
  int previous_run = 0, skeleton_run = 0, previous_won = 0, iterations_previous = 0, iterations_skeleton = 0,
      extrapolated = 0;
  for (const Stats& f : stats) {
    previous_run += f.iterations_previous > 0;
    skeleton_run += f.iterations_skeleton > 0;
    previous_won += f.previous_won;
    extrapolated += f.extrapolated;
    iterations_previous += f.iterations_previous;
    iterations_skeleton += f.iterations_skeleton;
  }
  std::printf(
      "starts: previous frame %d (mean %.1f iterations), skeleton %d (mean %.1f iterations); previous won %d; "
      "constant-velocity start %d\n",
      previous_run, previous_run ? static_cast<double>(iterations_previous) / previous_run : 0.0, skeleton_run,
      skeleton_run ? static_cast<double>(iterations_skeleton) / skeleton_run : 0.0, previous_won, extrapolated);
}

void write_stats_csv(const char* path, const std::vector<session::BodyFitFrameStats>& stats) {
  std::FILE* f = std::fopen(path, "w");
  if (!f) return;
  std::fprintf(f,
               "t_us,total_ms,observation_ms,fit_previous_ms,fit_skeleton_ms,it_previous,it_skeleton,E_previous,E_"
               "skeleton,previous_won\n");
  for (const auto& s : stats)
    std::fprintf(f, "%lld,%.3f,%.3f,%.3f,%.3f,%d,%d,%.4g,%.4g,%d\n", static_cast<long long>(s.t_us), 1e3 * s.total_s(),
                 1e3 * s.observation.total_s(), 1e3 * s.fit_previous_s, 1e3 * s.fit_skeleton_s, s.iterations_previous,
                 s.iterations_skeleton, s.energy_previous, s.energy_skeleton, s.previous_won ? 1 : 0);
  std::fclose(f);
}

void write_overlay(const std::string& path, const sim::CameraSessionResult& sim, size_t i, const v1::FrameResult& fit) {
  const raycast::DepthCamera camera{raycast::DepthIntrinsics{}};
  cv::Mat depth;
  for (const auto& c : sim.chunks) {
    if (c.has_depth() && c.depth().t_us() == sim.t_us[i]) depth = session::decode_depth(c.depth());
  }
  cv::Mat gray(depth.rows, depth.cols, CV_8UC1);
  for (int r = 0; r < depth.rows; ++r) {
    for (int c = 0; c < depth.cols; ++c) {
      const double z = depth.at<std::uint16_t>(r, c) * 1e-3;
      gray.at<std::uint8_t>(r, c) =
          z <= 0 ? 0 : static_cast<std::uint8_t>(std::clamp(255 - (z - 1.5) * 100, 20.0, 255.0));
    }
  }
  cv::Mat image;
  cv::cvtColor(gray, image, cv::COLOR_GRAY2BGR);
  cv::resize(image, image, cv::Size(), 2, 2, cv::INTER_NEAREST);
  const auto draw = [&](const Eigen::Vector3d& p, const cv::Scalar& colour, int radius) {
    if (const auto px = camera.project(p)) cv::circle(image, cv::Point2d(2 * px->x(), 2 * px->y()), radius, colour, 2);
  };
  const v1::SkeletonFrame* skeleton = nullptr;
  for (const auto& c : sim.chunks) {
    if (c.has_skeleton() && c.skeleton().t_us() == sim.t_us[i]) skeleton = &c.skeleton();
  }
  for (int k = 0; k < kKinds; ++k) {
    for (int s = 0; s < 2; ++s) {
      draw(sim.truth[i].smpl_joints_K.col(kSmplJoints[k][s]), cv::Scalar(255, 80, 0), 9);  // truth: blue
      if (skeleton)
        draw(vec(skeleton->joints(kCameraJoints[k][s]).position_m()), cv::Scalar(0, 0, 255), 6);  // camera: red
      draw(vec(fit.smpl_joints(kSmplJoints[k][s]).position_m()), cv::Scalar(0, 200, 0), 3);       // fit: green
    }
  }
  cv::putText(image, "blue: truth  red: camera skeleton  green: fit", {10, 24}, cv::FONT_HERSHEY_SIMPLEX, 0.6,
              cv::Scalar(255, 255, 255), 1);
  cv::imwrite(path, image);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> positional;
  std::vector<std::string> exercises = {"arm_raising",  "shoulder_lift", "forearm_rolling",
                                        "hair_combing", "torso_tilt",    "air_punching"};
  double max_seconds = 1e9;
  std::uint64_t seed_base = 0;
  int subjects = 1;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "--no-fine-shape") {
      g_fine_shape = false;
    } else if (arg.rfind("--exercises=", 0) == 0) {
      exercises.clear();
      std::string list = arg.substr(12);
      for (size_t start = 0; start <= list.size();) {
        const size_t comma = std::min(list.find(',', start), list.size());
        exercises.push_back(list.substr(start, comma - start));
        start = comma + 1;
      }
    } else if (arg.rfind("--lambda-imu=", 0) == 0) {
      g_lambda_imu = arg.substr(13);
    } else if (arg.rfind("--subjects=", 0) == 0) {
      subjects = std::max(1, std::atoi(arg.c_str() + 11));
    } else if (arg.rfind("--seed-base=", 0) == 0) {
      seed_base = std::strtoull(arg.c_str() + 12, nullptr, 10);
    } else if (arg.rfind("--max-seconds=", 0) == 0) {
      max_seconds = std::atof(arg.c_str() + 14);
    } else {
      positional.push_back(arg);
    }
  }
  const double rate_hz = positional.size() > 0 ? std::atof(positional[0].c_str()) : 5.0;
  const std::string overlay = positional.size() > 1 ? positional[1] : "";
  const std::string mocap_dir = positional.size() > 2 ? positional[2] : "";
  // Paper 2's exercises, then (with a mocap folder) the first kClipS seconds of two upper-body clips.
  std::vector<sim::BodyMotion> motions;
  sim::ExerciseOptions exercise_options;
  exercise_options.repetitions = 1;
  exercise_options.rest_hold_s = 0.5;
  for (const auto& name : exercises) {
    motions.push_back(sim::make_exercise(name, exercise_options));
    motions.back().duration_s = std::min(motions.back().duration_s, max_seconds);
  }
  if (!mocap_dir.empty()) {
    constexpr double kClipS = 10.0;
    for (const char* clip : {"wipe", "box-1"}) {
      exercises.push_back(std::string("mocap ") + clip);
      motions.push_back(sim::bvh_motion(sim::load_bvh(mocap_dir + "/" + clip + ".bvh")));
      motions.back().duration_s = std::min(motions.back().duration_s, kClipS);
    }
  }
  const body::PoseLayout layout = body::PoseLayout::all_joints();
  const int left_z = layout.index_of("left_shoulder_z"), right_z = layout.index_of("right_shoulder_z");
  Table total;
  std::printf(
      "bench_fig4: %.1f Hz subsampling, 1 s controlled pose + each exercise (1 repetition, at most %.1f s), fine shape "
      "%s\n",
      rate_hz, std::min(max_seconds, 999.0), g_fine_shape ? "on" : "off");
  bool overlay_written = false;
  const std::vector<std::string> all_exercises = {"arm_raising", "shoulder_lift", "forearm_rolling", "hair_combing",
                                                  "torso_tilt",  "air_punching",  "mocap wipe",      "mocap box-1"};
  // Each exercise once per subject: the seed base picks the subject, render and IMU errors.
  const size_t distinct = exercises.size();
  std::vector<std::uint64_t> seed_bases(distinct, seed_base);
  for (int k = 1; k < subjects; ++k)
    for (size_t e = 0; e < distinct; ++e) {
      const std::string name = exercises[e];
      const sim::BodyMotion motion = motions[e];
      exercises.push_back(name);
      motions.push_back(motion);
      seed_bases.push_back(seed_base + static_cast<std::uint64_t>(k));
    }
  for (size_t e = 0; e < exercises.size(); ++e) {
    const sim::BodyMotion& motion = motions[e];
    // Seeds by the exercise's place in the full list, so that a subset sees the same sessions.
    const size_t seed_index = static_cast<size_t>(std::find(all_exercises.begin(), all_exercises.end(), exercises[e]) -
                                                  all_exercises.begin()) +
                              1000 * seed_bases[e];
    Eigen::VectorXd controlled = motion.poses(0.0);
    controlled[left_z] = -45 * kDeg;
    controlled[right_z] = 45 * kDeg;
    sim::CameraSessionOptions options;
    options.rate_hz = rate_hz;
    options.duration_s = kCalibrationS + motion.duration_s;
    options.seed = 100 + seed_index;
    std::mt19937_64 rng(200 + seed_index);
    std::uniform_real_distribution<double> beta(-1.5, 1.5);
    for (int b = 0; b < 4; ++b) options.betas[b] = beta(rng);
    options.forearm_straps = {sim::ForearmStrap{sim::BodySide::kRight}, sim::ForearmStrap{sim::BodySide::kLeft}};
    const sim::CameraSessionResult sim = sim::simulate_camera_session(
        options, layout, [&](double t) { return t < kCalibrationS ? controlled : motion.poses(t - kCalibrationS); });

    Table table;
    const Output with_imu = run_stage(sim, forearm_batches(sim, 300 + seed_index), &table.frame_s, &table.stats);
    const Output without_imu = run_stage(sim, {}, nullptr, nullptr);
    for (const auto& c : sim.chunks) {
      if (!c.has_skeleton() || static_cast<double>(c.skeleton().t_us()) * 1e-6 < kCalibrationS) continue;
      const size_t i =
          static_cast<size_t>(std::find(sim.t_us.begin(), sim.t_us.end(), c.skeleton().t_us()) - sim.t_us.begin());
      const auto fit = with_imu.frames.find(sim.t_us[i]);
      const auto fit_no_imu = without_imu.frames.find(sim.t_us[i]);
      if (fit == with_imu.frames.end() || fit_no_imu == without_imu.frames.end()) continue;
      const auto& truth = sim.truth[i];
      const bool occluded = truth.forearms[0].occluded || truth.forearms[1].occluded;
      ++table.frames;
      table.occluded += occluded;
      for (int k = 0; k < kKinds; ++k) {
        for (int s = 0; s < 2; ++s) {
          const Eigen::Vector3d t = truth.smpl_joints_K.col(kSmplJoints[k][s]);
          const double camera = (vec(c.skeleton().joints(kCameraJoints[k][s]).position_m()) - t).norm();
          const double f = (vec(fit->second.smpl_joints(kSmplJoints[k][s]).position_m()) - t).norm();
          const double g = (vec(fit_no_imu->second.smpl_joints(kSmplJoints[k][s]).position_m()) - t).norm();
          for (Table* tb : {&table, &total}) {
            tb->camera.add(k, camera);
            tb->fit.add(k, f);
            tb->fit_no_imu.add(k, g);
            if (occluded) {
              tb->camera_occ.add(k, camera);
              tb->fit_occ.add(k, f);
              tb->fit_no_imu_occ.add(k, g);
            }
          }
        }
      }
      if (exercises[e] == "shoulder_lift") {
        for (int s = 0; s < 2; ++s) {
          const auto p = [&](int j) { return vec(fit->second.smpl_joints(j).position_m()); };
          const auto q = [&](int j) { return vec(c.skeleton().joints(j).position_m()); };
          const double true_elevation =
              elevation_deg(truth.smpl_joints_K.col(body::kPelvis), truth.smpl_joints_K.col(body::kNeck),
                            truth.smpl_joints_K.col(kSmplJoints[0][s]));
          const double fit_error =
              elevation_deg(p(body::kPelvis), p(body::kNeck), p(kSmplJoints[0][s])) - true_elevation;
          total.elevation_fit += std::abs(fit_error);
          total.elevation_fit_signed += fit_error;
          total.elevation_camera += std::abs(elevation_deg(q(0), q(2), q(kCameraJoints[0][s])) - true_elevation);
          ++total.elevation_n;
        }
      }
      // Hand over the head, half way through the combing exercise.
      if (!overlay.empty() && !overlay_written && exercises[e] == "hair_combing" &&
          static_cast<double>(sim.t_us[i]) * 1e-6 > kCalibrationS + 0.45 * motion.duration_s) {
        write_overlay(overlay, sim, i, fit->second);
        overlay_written = true;
      }
    }
    total.frame_s.insert(total.frame_s.end(), table.frame_s.begin(), table.frame_s.end());
    const auto& shape = with_imu.report.body_shape();
    std::printf("%-17s shape betas 0-3 true", exercises[e].c_str());
    for (int b = 0; b < 4; ++b) std::printf(" %+.2f", options.betas[b]);
    std::printf(", fitted");
    for (int b = 0; b < std::min(10, shape.betas_size()); ++b) std::printf(" %+.2f", shape.betas(b));
    // What the shape does to the skeleton: the six upper-limb rest joints relative to the pelvis,
    // fitted shape and template shape against the subject's.
    const auto model = body::make_template(body::Sex::kMale);
    Eigen::VectorXd fitted_beta = Eigen::VectorXd::Zero(model->num_betas());
    for (int b = 0; b < std::min<int>(model->num_betas(), shape.betas_size()); ++b) fitted_beta[b] = shape.betas(b);
    const auto rest_error_mm = [&](const Eigen::VectorXd& beta) {
      const Eigen::Matrix3Xd a = fit::rest_joints(*model, beta), t = fit::rest_joints(*model, options.betas);
      double sum = 0;
      for (int k = 0; k < kKinds; ++k)
        for (int side = 0; side < 2; ++side) {
          const int j = kSmplJoints[k][side];
          sum += ((a.col(j) - a.col(body::kPelvis)) - (t.col(j) - t.col(body::kPelvis))).norm();
        }
      return 1e3 * sum / (2 * kKinds);
    };
    std::printf(" (%s); upper-limb rest joints off by %.1f mm (template shape %.1f mm)\n",
                shape.estimated() ? "personalised" : "template", rest_error_mm(fitted_beta),
                rest_error_mm(Eigen::VectorXd::Zero(model->num_betas())));
    // The arm segments' lengths (shoulder-elbow, elbow-wrist; left, then right) against the
    // subject's: the error measures.arm_length_uncertainty stands for (docs/measures.md).
    const auto segment_errors = [&](const Eigen::VectorXd& beta) {
      const Eigen::Matrix3Xd a = fit::rest_joints(*model, beta), t = fit::rest_joints(*model, options.betas);
      std::vector<double> out;
      // A segment runs from kind `from` to kind `to` (0 shoulder, 1 elbow, 2 wrist): upper arm,
      // forearm, then the whole arm (shoulder-wrist, which a straight arm shows).
      for (int side = 0; side < 2; ++side)
        for (const auto& [from_kind, to_kind] : {std::pair{0, 1}, std::pair{1, 2}, std::pair{0, 2}}) {
          const int from = kSmplJoints[from_kind][side], to = kSmplJoints[to_kind][side];
          out.push_back((a.col(to) - a.col(from)).norm() / (t.col(to) - t.col(from)).norm() - 1);
        }
      return out;
    };
    const std::vector<double> fitted_segments = segment_errors(fitted_beta);
    const std::vector<double> template_segments = segment_errors(Eigen::VectorXd::Zero(model->num_betas()));
    std::printf("%-17s arm lengths (upper, fore, whole; left, right) fitted", exercises[e].c_str());
    for (double r : fitted_segments) std::printf(" %+.1f %%", 100 * r);
    std::printf(", template");
    for (double r : template_segments) std::printf(" %+.1f %%", 100 * r);
    std::printf("\n");
    std::vector<double>& fitted_list = shape.estimated() ? total.segments_personalised : total.segments_refused;
    fitted_list.insert(fitted_list.end(), fitted_segments.begin(), fitted_segments.end());
    if (shape.estimated())
      total.segments_template_where_personalised.insert(total.segments_template_where_personalised.end(),
                                                        template_segments.begin(), template_segments.end());
    total.stats.insert(total.stats.end(), table.stats.begin(), table.stats.end());
    std::printf("%-17s frames %3d (occluded %3d)  camera %5.1f mm  fit %5.1f mm  fit w/o imu %5.1f mm\n",
                exercises[e].c_str(), table.frames, table.occluded, 1e3 * table.camera.mean_all(),
                1e3 * table.fit.mean_all(), 1e3 * table.fit_no_imu.mean_all());
    total.frames += table.frames;
    total.occluded += table.occluded;
  }
  std::printf("\nFig. 4, all exercises: %d frames, %d with an occluded forearm\n", total.frames, total.occluded);
  std::printf("| joints | camera all | fit all | fit w/o imu all | camera occl. | fit occl. | fit w/o imu occl. |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (int k = 0; k <= kKinds; ++k) {
    const auto m = [&](const Sums& s) { return 1e3 * (k < kKinds ? s.mean(k) : s.mean_all()); };
    std::printf("| %s | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f |\n", k < kKinds ? kKindNames[k] : "all six",
                m(total.camera), m(total.fit), m(total.fit_no_imu), m(total.camera_occ), m(total.fit_occ),
                m(total.fit_no_imu_occ));
  }
  const double lower_all = 100 * (1 - total.fit.mean_all() / total.camera.mean_all());
  const double lower_occ = 100 * (1 - total.fit_occ.mean_all() / total.camera_occ.mean_all());
  std::printf("fit vs camera skeleton: %.1f %% lower overall, %.1f %% lower under occlusion\n", lower_all, lower_occ);
  std::printf("dropping the imu term: wrists %+.1f %%, elbows %+.1f %% under occlusion\n",
              100 * (total.fit_no_imu_occ.mean(2) / total.fit_occ.mean(2) - 1),
              100 * (total.fit_no_imu_occ.mean(1) / total.fit_occ.mean(1) - 1));
  if (total.elevation_n > 0) {
    std::printf(
        "shoulder_lift: shoulder elevation error fit %.1f deg (signed mean %+.1f), camera skeleton %.1f deg (%d "
        "shoulder-frames)\n",
        total.elevation_fit / total.elevation_n, total.elevation_fit_signed / total.elevation_n,
        total.elevation_camera / total.elevation_n, total.elevation_n);
  }
  // RMS and largest magnitude in per cent of the segments (whole = false: upper arms and forearms)
  // or the whole arms.
  const auto rms_and_max = [](const std::vector<double>& v, bool whole) {
    double sum = 0, largest = 0;
    int n = 0;
    for (size_t k = 0; k < v.size(); ++k) {
      if ((k % 3 == 2) != whole) continue;
      sum += v[k] * v[k];
      largest = std::max(largest, std::abs(v[k]));
      ++n;
    }
    return std::pair<double, double>{n ? 100 * std::sqrt(sum / n) : NAN, n ? 100 * largest : NAN};
  };
  for (const bool whole : {false, true}) {
    const auto [personalised_rms, personalised_max] = rms_and_max(total.segments_personalised, whole);
    const auto [template_rms, template_max] = rms_and_max(total.segments_template_where_personalised, whole);
    const auto [refused_rms, refused_max] = rms_and_max(total.segments_refused, whole);
    std::printf(
        "%s lengths (RMS / max): personalised in %zu sessions %.1f %% / %.1f %%, the template shape in the same "
        "sessions %.1f %% / %.1f %%; template where refused (%zu sessions) %.1f %% / %.1f %%\n",
        whole ? "whole arm" : "upper arm and forearm", total.segments_personalised.size() / 6, personalised_rms,
        personalised_max, template_rms, template_max, total.segments_refused.size() / 6, refused_rms, refused_max);
  }
  std::printf(
      "time per frame (thread CPU of the calling thread per skeleton chunk): median %.1f ms, p95 %.1f ms (%zu "
      "frames)\n",
      1e3 * percentile(total.frame_s, 0.5), 1e3 * percentile(total.frame_s, 0.95), total.frame_s.size());
  print_phases(total.stats);
  if (const char* csv = std::getenv("FIG4_STATS_CSV")) write_stats_csv(csv, total.stats);
  return 0;
}
