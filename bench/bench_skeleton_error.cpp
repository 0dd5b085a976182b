// The simulator's camera skeleton (core/sim/camera_skeleton.hpp) measured the way Kinect v2
// studies measure the SDK against mocap: whole simulated sessions (simulate_session, default
// options but no colour stream, which the skeleton does not see), each exercise played once
// at its own length, the reported joints against the error-free camera joints of the truth.
//
//   build/bench/bench_skeleton_error [seeds=3]
//   [exercises=arm_raising,shoulder_lift,forearm_rolling,hair_combing,torso_tilt,air_punching,forearm_protocol]
//
// Seeds 1..seeds are reporting seeds: nothing is tuned on them (the bench changes no model
// parameter). Prints, for shoulders, elbows, wrists and hands (left and right pooled):
//  - bias (norm of the mean error vector per session), spread (RMS distance from that mean),
//    mean |e|, each averaged over sessions and both sides (eval/skeleton_errors.hpp);
//  - tracking states (TRACKED / INFERRED / NOT_TRACKED) over all frames, and while that arm's
//    forearm is occluded in the camera's view (the truth's forearm_visible_fraction < 0.5, as
//    gt/occlusion.csv's forearm_occluded) or visible, with the mean |e| per state;
//  - the off-track rate: frames where a joint leaves its own 5-frame running median by more
//    than 0.1 m (a jump out and back), per joint group and for any of the eight joints;
//  - the trunk's joints' tracking states (SpineBase, SpineMid, SpineShoulder, Neck, hips).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "bench_clock.hpp"
#include "eval/skeleton_errors.hpp"
#include "geometry/kinect_joints.hpp"
#include "sim/sim_session.hpp"

namespace {

using namespace posefuse;
using geometry::Vec3;
using enum geometry::KinectJoint;

constexpr double kOffTrackM = 0.10;
constexpr int kHalfWindow = 2;

// Shoulders, elbows, wrists, hands: {left, right}.
constexpr int kGroups = 4;
constexpr const char* kGroupNames[kGroups] = {"shoulders", "elbows", "wrists", "hands"};
constexpr int kGroupJoints[kGroups][2] = {
    {kShoulderLeft, kShoulderRight}, {kElbowLeft, kElbowRight}, {kWristLeft, kWristRight}, {kHandLeft, kHandRight}};

constexpr int kTrunkJoints = 6;
constexpr const char* kTrunkNames[kTrunkJoints] = {"SpineBase", "SpineMid", "SpineShoulder",
                                                   "Neck",      "HipLeft",  "HipRight"};
constexpr int kTrunk[kTrunkJoints] = {kSpineBase, kSpineMid, kSpineShoulder, kNeck, kHipLeft, kHipRight};

class SkeletonSink : public session::ChunkSink {
 public:
  void write(const session::SessionChunk& chunk) override {
    if (chunk.has_skeleton()) frames[chunk.skeleton().t_us()] = chunk.skeleton();
  }
  void finish() override {}
  std::map<std::int64_t, v1::SkeletonFrame> frames;
};

struct StateCount {
  std::size_t n[4] = {0, 0, 0, 0};  // by v1::SkeletonJoint::State
  double error_sum[4] = {0, 0, 0, 0};
  void add(int state, double error_m) {
    if (state < 0 || state > 3) state = 0;
    ++n[state];
    error_sum[state] += error_m;
  }
  std::size_t total() const { return n[0] + n[1] + n[2] + n[3]; }
  double mean_mm(int state) const { return n[state] ? 1e3 * error_sum[state] / static_cast<double>(n[state]) : NAN; }
};

enum Condition { kAll = 0, kOccluded, kVisible, kConditions };
constexpr const char* kConditionNames[kConditions] = {"all frames", "forearm occluded", "forearm visible"};

struct Totals {
  // Per group: sums over (session, side) of bias, spread, mean |e|; and the range of the
  // per-session group mean |e|.
  double bias[kGroups] = {}, spread[kGroups] = {}, mean_abs[kGroups] = {};
  double mean_abs_min[kGroups], mean_abs_max[kGroups];
  int samples[kGroups] = {};
  std::size_t off_track[kGroups] = {}, joint_frames[kGroups] = {};
  std::size_t frames = 0, frames_any_off = 0, occluded_arm_frames = 0, arm_frames = 0;
  StateCount states[kConditions][kGroups];
  StateCount trunk[kTrunkJoints];
  Totals() {
    for (int g = 0; g < kGroups; ++g) mean_abs_min[g] = 1e9, mean_abs_max[g] = -1e9;
  }
};

double pct(std::size_t a, std::size_t b) {
  return b == 0 ? NAN : 100.0 * static_cast<double>(a) / static_cast<double>(b);
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, ',');) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

Vec3 position(const v1::SkeletonFrame& f, int j) {
  const auto& p = f.joints(j).position_m();
  return {p.x(), p.y(), p.z()};
}

}  // namespace

int main(int argc, char** argv) {
  const int seeds = argc > 1 ? std::atoi(argv[1]) : 3;
  const std::vector<std::string> exercises = split(
      argc > 2 ? argv[2]
               : "arm_raising,shoulder_lift,forearm_rolling,hair_combing,torso_tilt,air_punching,forearm_protocol");
  if (seeds < 1 || exercises.empty()) {
    std::fprintf(stderr, "usage: bench_skeleton_error [seeds>=1] [exercise,exercise,...]\n");
    return 2;
  }
  Totals t;
  const auto start = bench::WallClock::now();
  std::printf(
      "| exercise | seed | frames | right forearm occluded | left forearm occluded |\n| --- | --- | --- | --- | --- "
      "|\n");
  for (const std::string& exercise : exercises) {
    for (int seed = 1; seed <= seeds; ++seed) {
      sim::SimSessionOptions options;
      options.seed = static_cast<std::uint64_t>(seed);
      options.motion = exercise;
      options.motion_options.exercise.repetitions = 1;
      options.duration_from_motion = true;
      options.color = false;
      SkeletonSink sink;
      sim::SimTruth truth;
      try {
        truth = sim::simulate_session(options, sink);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_skeleton_error: %s seed %d: %s\n", exercise.c_str(), seed, e.what());
        return 1;
      }
      // Per joint: the error series over the session's frames.
      std::vector<Vec3> errors[kGroups][2];
      std::vector<bool> occluded[2];
      std::size_t occluded_frames[2] = {0, 0};
      for (const sim::SimFrameTruth& frame : truth.frames) {
        const auto it = sink.frames.find(frame.t_us);
        if (it == sink.frames.end()) continue;
        const v1::SkeletonFrame& skeleton = it->second;
        for (int k = 0; k < kTrunkJoints; ++k) {
          const int j = kTrunk[k];
          t.trunk[k].add(static_cast<int>(skeleton.joints(j).state()),
                         (position(skeleton, j) - frame.camera_joints_K.col(j)).norm());
        }
        for (int side = 0; side < 2; ++side) {
          const bool occ = frame.forearm_visible_fraction[static_cast<std::size_t>(side)] < 0.5;
          occluded[side].push_back(occ);
          occluded_frames[side] += occ ? 1 : 0;
          for (int g = 0; g < kGroups; ++g) {
            const int j = kGroupJoints[g][side];
            const Vec3 e = position(skeleton, j) - frame.camera_joints_K.col(j);
            errors[g][side].push_back(e);
            const int state = static_cast<int>(skeleton.joints(j).state());
            t.states[kAll][g].add(state, e.norm());
            t.states[occ ? kOccluded : kVisible][g].add(state, e.norm());
          }
        }
      }
      const std::size_t n = errors[0][0].size();
      std::printf("| %s | %d | %zu | %.1f %% | %.1f %% |\n", exercise.c_str(), seed, n, pct(occluded_frames[1], n),
                  pct(occluded_frames[0], n));
      t.frames += n;
      t.arm_frames += 2 * n;
      t.occluded_arm_frames += occluded_frames[0] + occluded_frames[1];
      std::vector<bool> any_off(n, false);
      for (int g = 0; g < kGroups; ++g) {
        double session_mean_abs = 0;
        for (int side = 0; side < 2; ++side) {
          const eval::JointErrorStats s = eval::joint_error_stats(errors[g][side], kOffTrackM, kHalfWindow);
          t.bias[g] += s.bias_m;
          t.spread[g] += s.spread_m;
          t.mean_abs[g] += s.mean_abs_m;
          session_mean_abs += 0.5 * s.mean_abs_m;
          ++t.samples[g];
          t.off_track[g] += s.off_track_frames;
          t.joint_frames[g] += s.frames;
          const std::vector<bool> off = eval::off_track_frames(errors[g][side], kOffTrackM, kHalfWindow);
          for (std::size_t k = 0; k < n; ++k) any_off[k] = any_off[k] || off[k];
        }
        t.mean_abs_min[g] = std::min(t.mean_abs_min[g], session_mean_abs);
        t.mean_abs_max[g] = std::max(t.mean_abs_max[g], session_mean_abs);
      }
      for (const bool b : any_off) t.frames_any_off += b ? 1 : 0;
    }
  }
  const double wall_s = bench::wall_ms_since(start) / 1e3;

  std::printf("\n%zu frames (30 Hz) over %zu sessions; arm forearm occluded in %.1f %% of arm-frames; wall %.0f s\n\n",
              t.frames, exercises.size() * static_cast<std::size_t>(seeds), pct(t.occluded_arm_frames, t.arm_frames),
              wall_s);
  std::printf(
      "| joints | bias mm | spread mm | mean abs error mm (range over sessions) | off track %% of frames |\n"
      "| --- | --- | --- | --- | --- |\n");
  for (int g = 0; g < kGroups; ++g) {
    const double k = 1e3 / t.samples[g];
    std::printf("| %s | %.1f | %.1f | %.1f (%.1f-%.1f) | %.2f |\n", kGroupNames[g], k * t.bias[g], k * t.spread[g],
                k * t.mean_abs[g], 1e3 * t.mean_abs_min[g], 1e3 * t.mean_abs_max[g],
                pct(t.off_track[g], t.joint_frames[g]));
  }
  std::printf("\nframes with any of the eight joints off track: %.2f %% (%zu of %zu)\n\n",
              pct(t.frames_any_off, t.frames), t.frames_any_off, t.frames);

  std::printf(
      "| condition | joints | joint-frames | TRACKED %% | INFERRED %% | NOT_TRACKED %% | mean abs error mm TRACKED / "
      "INFERRED |\n"
      "| --- | --- | --- | --- | --- | --- | --- |\n");
  for (int c = 0; c < kConditions; ++c) {
    for (int g = 0; g < kGroups; ++g) {
      const StateCount& s = t.states[c][g];
      std::printf("| %s | %s | %zu | %.1f | %.1f | %.1f | %.1f / %.1f |\n", kConditionNames[c], kGroupNames[g],
                  s.total(), pct(s.n[v1::SkeletonJoint::TRACKED], s.total()),
                  pct(s.n[v1::SkeletonJoint::INFERRED], s.total()), pct(s.n[v1::SkeletonJoint::NOT_TRACKED], s.total()),
                  s.mean_mm(v1::SkeletonJoint::TRACKED), s.mean_mm(v1::SkeletonJoint::INFERRED));
    }
  }
  std::printf(
      "\n| trunk joint | frames | TRACKED %% | INFERRED %% | mean abs error mm TRACKED / INFERRED |\n"
      "| --- | --- | --- | --- | --- |\n");
  for (int k = 0; k < kTrunkJoints; ++k) {
    const StateCount& s = t.trunk[k];
    std::printf("| %s | %zu | %.1f | %.1f | %.1f / %.1f |\n", kTrunkNames[k], s.total(),
                pct(s.n[v1::SkeletonJoint::TRACKED], s.total()), pct(s.n[v1::SkeletonJoint::INFERRED], s.total()),
                s.mean_mm(v1::SkeletonJoint::TRACKED), s.mean_mm(v1::SkeletonJoint::INFERRED));
  }
  return 0;
}
