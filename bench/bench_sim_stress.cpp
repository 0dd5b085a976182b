// Stress bench of the simulator's motion input (issue 22): does every motion simulate, and what
// does a simulated second cost?
//
//   build/bench/bench_sim_stress [mocap_folder=/work/shared/data/mocap] [--full]
//
// Cases, each a whole session (simulate_session, motion bvh, duration_s = clip) at playback
// speeds 0.5, 1 and 2:
//   swing-W    the 21-joint rig (tests/sim/test_rigs.hpp) swinging its right upper arm up and
//              down, +-1 rad, at a peak rate of W rad/s (5, 10, 20), 8 s;
//   roll-W     the right forearm rolling about its bone, +-1.5 rad, peak W rad/s, 8 s;
//   glitch-*   a 10 s clip (both arms swinging, the right forearm rolling) with glitches put in:
//              a 2-frame 180 degree forearm flip, an 8-frame flip, arms swapped for 15 frames
//              (while the arms are apart, and while they are near mirror images: a swap the
//              wrist test cannot see, docs/simulator.md), and a 30-frame flip (longer than bvh_max_glitch_frames = 12:
//              refused by design) also with bvh_max_glitch_frames = 40 (interpolated across);
//   CLIP       every .bvh file of the folder (skipped with a message when it is missing).
// By default the camera renders at a quarter of the Kinect's resolution (128 x 106) without
// colour, so the table measures the motion path (retargeting, 1 kHz poses, IMU synthesis) and
// the session around it; --full uses posefuse-sim's defaults (512 x 424 depth, 960 x 540
// colour). Columns: the true peak |omega| of the right IMU (between 80 Hz samples), wall and CPU
// (all threads, getrusage) seconds per simulated second, and ok or the refusal.
#include <sys/resource.h>

#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "bench_clock.hpp"
#include "common/error.hpp"
#include "sim/sim_session.hpp"
#include "sim/test_rigs.hpp"

namespace {

using namespace posefuse;
namespace rigs = posefuse::sim::testing;
using std::numbers::pi;

constexpr double kFrameTime = 1.0 / 60;

class NullSink : public session::ChunkSink {
 public:
  void write(const session::SessionChunk&) override { ++chunks; }
  void finish() override {}
  std::uint64_t chunks = 0;
};

double process_cpu_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

int joint_index(const std::vector<rigs::RigJointSpec>& rig, const std::string& name) {
  for (std::size_t j = 0; j < rig.size(); ++j) {
    if (rig[j].name == name) return static_cast<int>(j);
  }
  throw std::runtime_error(name);
}

// Degrees of a sine of amplitude `amplitude_rad` whose peak rate is `rate_rad_s`.
double sine_deg(double t, double amplitude_rad, double rate_rad_s, double phase = 0) {
  return amplitude_rad * std::sin(rate_rad_s / amplitude_rad * t + phase) * 180.0 / pi;
}

struct Case {
  std::string name;
  std::string path;  // BVH file
  int max_glitch_frames = 12;
};

// Channel values of the rig: root still at 95 cm, arms lowered 45 deg, plus `extra`.
rigs::RigValue at_rest_plus(const std::vector<rigs::RigJointSpec>& rig, rigs::RigValue extra) {
  const int left_arm = joint_index(rig, "LeftArm"), right_arm = joint_index(rig, "RightArm");
  return [=](int f, int j, int c) {
    double v = extra(f, j, c);
    if (rig[static_cast<std::size_t>(j)].root && c == 1) v += 95.0;
    if (j == left_arm && c == 0) v -= 45.0;
    if (j == right_arm && c == 0) v += 45.0;
    return v;
  };
}

std::string write_clip(const std::filesystem::path& dir, const std::string& name,
                       const std::vector<rigs::RigJointSpec>& rig, double seconds, const rigs::RigValue& value) {
  const std::filesystem::path path = dir / (name + ".bvh");
  std::ofstream(path) << rigs::rig_text(rig, static_cast<int>(std::lround(seconds / kFrameTime)) + 1, kFrameTime,
                                        value);
  return path.string();
}

std::vector<Case> synthetic_cases(const std::filesystem::path& dir) {
  std::vector<Case> cases;
  const auto rig = rigs::rig21();
  const int right_arm = joint_index(rig, "RightArm"), right_forearm = joint_index(rig, "RightForeArm");
  for (double rate : {5.0, 10.0, 20.0}) {
    const std::string w = std::to_string(static_cast<int>(rate));
    cases.push_back({"swing-" + w, write_clip(dir, "swing-" + w, rig, 8.0, at_rest_plus(rig, [=](int f, int j, int c) {
                                                return j == right_arm && c == 0 ? sine_deg(f * kFrameTime, 1.0, rate)
                                                                                : 0.0;
                                              }))});
    cases.push_back({"roll-" + w, write_clip(dir, "roll-" + w, rig, 8.0, at_rest_plus(rig, [=](int f, int j, int c) {
                                               return j == right_forearm && c == 2 ? sine_deg(f * kFrameTime, 1.5, rate)
                                                                                   : 0.0;
                                             }))});
  }
  // Glitches on a symmetric rig (an exact arm swap needs mirror-image arms).
  const auto sym = rigs::symmetric_rig21();
  const int l_arm = joint_index(sym, "LeftArm"), r_arm = joint_index(sym, "RightArm");
  const int r_fore = joint_index(sym, "RightForeArm");
  const rigs::RigValue base = at_rest_plus(sym, [=](int f, int j, int c) {
    const double t = f * kFrameTime;
    if (j == r_arm && c == 0) return sine_deg(t, 0.6, 3.0);
    if (j == l_arm && c == 0) return sine_deg(t, 0.5, 2.0, 1.0);
    if (j == l_arm && c == 1) return sine_deg(t, 0.3, 1.0);
    if (j == r_fore && c == 1) return 30.0 + sine_deg(t, 0.4, 2.0);
    if (j == r_fore && c == 2) return sine_deg(t, 1.2, 6.0);
    return 0.0;
  });
  const auto flipped = [=](int first, int last) -> rigs::RigValue {
    return [=](int f, int j, int c) {
      return base(f, j, c) + (j == r_fore && c == 2 && f >= first && f <= last ? 180.0 : 0.0);
    };
  };
  cases.push_back({"glitch-flip-2", write_clip(dir, "glitch-flip-2", sym, 10.0, flipped(300, 301))});
  cases.push_back({"glitch-flip-8", write_clip(dir, "glitch-flip-8", sym, 10.0, flipped(300, 307))});
  // Arms swapped while they do different things (the right one raised 30 deg, the left lowered
  // 45 deg), and while they are near mirror images of each other (both lowered 45 deg).
  const rigs::RigValue apart = [=](int f, int j, int c) { return base(f, j, c) - (j == r_arm && c == 0 ? 75.0 : 0.0); };
  cases.push_back({"glitch-swap-15, arms apart",
                   write_clip(dir, "glitch-swap-apart", sym, 10.0, rigs::with_arms_swapped(sym, apart, 200, 214))});
  cases.push_back({"glitch-swap-15, arms near mirror",
                   write_clip(dir, "glitch-swap-mirror", sym, 10.0, rigs::with_arms_swapped(sym, base, 200, 214))});
  const std::string long_flip = write_clip(dir, "glitch-flip-30", sym, 10.0, flipped(300, 329));
  cases.push_back({"glitch-flip-30", long_flip});
  cases.push_back({"glitch-flip-30, max_glitch_frames 40", long_flip, 40});
  return cases;
}

// The largest true turn rate of the right arm IMU between consecutive samples.
double peak_rate(const sim::SimTruth& truth) {
  for (const sim::SimDeviceTruth& d : truth.devices) {
    if (d.device_id != "imu_right") continue;
    double peak = 0;
    for (std::size_t k = 1; k < d.W_from_A.size(); ++k) {
      const double dt = d.t_camera_s[k] - d.t_camera_s[k - 1];
      if (dt > 0) peak = std::max(peak, d.W_from_A[k - 1].angularDistance(d.W_from_A[k]) / dt);
    }
    return peak;
  }
  return std::nan("");
}

std::string one_line(std::string s) {
  std::replace(s.begin(), s.end(), '\n', ' ');
  std::replace(s.begin(), s.end(), '|', '/');
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  std::filesystem::path folder = "/work/shared/data/mocap";
  bool full = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--full") full = true;
    else folder = a;
  }
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("bench_sim_stress_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::vector<Case> cases = synthetic_cases(dir);
  if (std::filesystem::is_directory(folder)) {
    std::vector<std::filesystem::path> clips;
    for (const auto& e : std::filesystem::directory_iterator(folder)) {
      if (e.path().extension() == ".bvh") clips.push_back(e.path());
    }
    std::sort(clips.begin(), clips.end());
    for (const auto& p : clips) cases.push_back({p.stem().string(), p.string()});
  } else {
    std::printf("(no folder %s: the shared clips are skipped)\n", folder.c_str());
  }

  std::printf("camera: %s\n\n", full ? "posefuse-sim defaults (512 x 424 depth, 960 x 540 colour)"
                                     : "128 x 106 depth, no colour (--full: posefuse-sim defaults)");
  std::printf(
      "| case | speed | simulated s | peak \\|ω\\| right IMU, rad/s | wall s per simulated s | CPU s per simulated s | "
      "result |\n");
  std::printf("| --- | --- | --- | --- | --- | --- | --- |\n");
  std::fflush(stdout);
  int refused = 0;
  double total_simulated = 0, total_wall = 0, total_cpu = 0;
  for (const Case& c : cases) {
    for (double speed : {0.5, 1.0, 2.0}) {
      sim::SimSessionOptions options;
      options.motion = "bvh";
      options.motion_options.bvh_path = c.path;
      options.motion_options.exercise.speed = speed;
      options.motion_options.bvh_glitches.max_glitch_frames = c.max_glitch_frames;
      options.duration_from_motion = true;
      if (!full) {
        options.color = false;
        options.depth_intrinsics.width = 128;
        options.depth_intrinsics.height = 106;
        options.depth_intrinsics.fx = options.depth_intrinsics.fy = 365.0 / 4;
        options.depth_intrinsics.cx = 64.0;
        options.depth_intrinsics.cy = 53.0;
      }
      NullSink sink;
      const auto start = bench::WallClock::now();
      const double cpu_start = process_cpu_s();
      std::string result = "ok";
      double simulated = 0, peak = std::nan("");
      try {
        const sim::SimTruth truth = sim::simulate_session(options, sink);
        simulated = truth.options.duration_s;
        peak = peak_rate(truth);
        if (!truth.warnings.empty()) {
          // "<path>: bvh frames a..b (...), <joint>: <reason>; repaired by <how>": frames and joint.
          for (const std::string& w : truth.warnings) {
            const std::size_t from = w.find("bvh frames");
            const std::size_t to = w.find(": ", from);
            result += "; repaired " + one_line(w.substr(from, to - from));
          }
        }
      } catch (const Error& e) {
        result = "refused: " + one_line(e.what());
        if (const auto at = result.find(dir.string() + "/"); at != std::string::npos)
          result.erase(at, dir.string().size() + 1);
        ++refused;
      } catch (const std::exception& e) {
        result = "failed: " + one_line(e.what());
        ++refused;
      }
      const double wall = bench::wall_ms_since(start) / 1e3, cpu = process_cpu_s() - cpu_start;
      if (simulated > 0) {
        total_simulated += simulated;
        total_wall += wall;
        total_cpu += cpu;
        std::printf("| %s | %g | %.2f | %.1f | %.3f | %.3f | %s |\n", c.name.c_str(), speed, simulated, peak,
                    wall / simulated, cpu / simulated, result.c_str());
      } else {
        std::printf("| %s | %g | - | - | - | - | %s |\n", c.name.c_str(), speed, result.c_str());
      }
      std::fflush(stdout);
    }
  }
  std::printf("\n%.1f simulated s in %.1f s wall, %.1f s CPU (%.3f / %.3f per simulated s); %d case(s) not simulated\n",
              total_simulated, total_wall, total_cpu, total_wall / total_simulated, total_cpu / total_simulated,
              refused);
  std::filesystem::remove_all(dir);
  return 0;
}
