// Mocap glitches in the real clips (core/sim/bvh_glitches.hpp): per file, every repaired
// glitch as posefuse-sim reports it, then the fastest local joint step left after the repair
// (rad/s, and which joint and frame), the margin below BvhGlitchOptions::max_joint_rate_rad_s.
//
//   build/bench/bench_sim_bvh_glitches [folder=../shared/data/mocap] [max_joint_rate_rad_s=60]
//
// The clips are not part of the repository: when the folder is missing the program says so
// and exits 0.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "sim/bvh.hpp"
#include "sim/bvh_glitches.hpp"

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  using namespace posefuse::sim;
  const fs::path folder = argc > 1 ? fs::path(argv[1]) : fs::path("../shared/data/mocap");
  BvhGlitchOptions options;
  if (argc > 2) options.max_joint_rate_rad_s = std::atof(argv[2]);
  if (!fs::is_directory(folder)) {
    std::printf("bench_sim_bvh_glitches: %s not found, skipping\n", folder.string().c_str());
    return 0;
  }
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.is_regular_file() && entry.path().extension() == ".bvh") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  int failures = 0;
  for (const fs::path& path : files) {
    try {
      const BvhClip clip = load_bvh(path);
      const BvhRepair repair = repair_bvh_glitches(clip, options);
      for (const BvhGlitch& g : repair.glitches) {
        std::printf("%s: %s\n", path.filename().string().c_str(), describe(g, clip.frame_time_s).c_str());
      }
      double fastest = 0;
      std::size_t fastest_joint = 0;
      std::size_t fastest_frame = 0;
      for (std::size_t f = 1; f < repair.clip.frames.size(); ++f) {
        for (std::size_t j = 0; j < clip.skeleton.joints.size(); ++j) {
          const double step = posefuse::geometry::angle_between(repair.clip.frames[f - 1].parent_from_joint[j],
                                                                repair.clip.frames[f].parent_from_joint[j]);
          if (step > fastest) {
            fastest = step;
            fastest_joint = j;
            fastest_frame = f;
          }
        }
      }
      std::printf("%s: %zu glitches; fastest step left %.1f rad/s (%s, frame %zu)\n", path.filename().string().c_str(),
                  repair.glitches.size(), fastest / clip.frame_time_s, clip.skeleton.joints[fastest_joint].name.c_str(),
                  fastest_frame);
    } catch (const posefuse::Error& e) {
      std::printf("%s: refused: %s: %s\n", path.filename().string().c_str(), e.field().c_str(), e.what());
      ++failures;
    }
  }
  return failures == 0 ? 0 : 1;
}
