// BVH loading speed on the real clips: per file, joints, frames, rate, parse time, forward
// kinematics time over all frames and resampling to 30 Hz; then an ideal wrist IMU on the
// right forearm (time, largest angular rate in rad/s and specific force in m/s^2).
//
//   build/bench/bench_sim_bvh [folder=../shared/data/mocap] [wrist IMU smoothing_s=0.02]
//
// The clips are not part of the repository: when the folder is missing the program says so
// and exits 0 (CI keeps them at ../shared relative to the repository).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "bench_clock.hpp"
#include "common/error.hpp"
#include "sim/bvh.hpp"
#include "sim/bvh_sensor.hpp"
#include "sim/imu_synth.hpp"

namespace {
using Clock = posefuse::bench::WallClock;
using posefuse::bench::wall_ms_since;
}  // namespace

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  const fs::path folder = argc > 1 ? fs::path(argv[1]) : fs::path("../shared/data/mocap");
  const double smoothing_s = argc > 2 ? std::atof(argv[2]) : 0.02;
  if (!fs::is_directory(folder)) {
    std::printf("bench_sim_bvh: %s not found, skipping\n", folder.string().c_str());
    return 0;
  }
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.is_regular_file() && entry.path().extension() == ".bvh") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  std::printf("%-22s %6s %7s %7s %9s %9s %12s %12s %12s %12s %8s %8s\n", "file", "joints", "frames", "fps", "length_s",
              "parse_ms", "fk_all_ms", "resample30_ms", "head-hips_m", "wrist_imu_ms", "max_gyr", "max_acc");
  int failures = 0;
  for (const fs::path& path : files) {
    try {
      auto start = Clock::now();
      const posefuse::sim::BvhClip clip = posefuse::sim::load_bvh(path);
      const double parse_ms = wall_ms_since(start);
      start = Clock::now();
      // A plausibility check of the Y-up -> Z-up mapping: the head is above the hips in W.
      const int head = clip.skeleton.find("Head");
      const int hips = clip.skeleton.find("Hips");
      double head_above_hips_m = 0.0;
      for (const auto& frame : clip.frames) {
        const auto pose = posefuse::sim::forward_kinematics(clip.skeleton, frame, 0.01);
        if (head >= 0 && hips >= 0) {
          head_above_hips_m +=
              pose.p_W_m[static_cast<std::size_t>(head)].z() - pose.p_W_m[static_cast<std::size_t>(hips)].z();
        }
      }
      head_above_hips_m /= static_cast<double>(clip.frames.size());
      const double fk_ms = wall_ms_since(start);
      start = Clock::now();
      const posefuse::sim::BvhClip resampled = posefuse::sim::resample(clip, 30.0);
      const double resample_ms = wall_ms_since(start);

      // An ideal wrist IMU on the right forearm, 80 % of the way to the hand, at 80 Hz.
      double imu_ms = 0.0, max_rate = 0.0, max_force = 0.0;
      const int hand = clip.skeleton.find("RightHand");
      if (hand >= 0) {
        start = Clock::now();
        posefuse::sim::BvhSensorMount mount;
        mount.joint = "RightForeArm";
        mount.offset_joint_m = 0.8 * 0.01 * clip.skeleton.joints[static_cast<std::size_t>(hand)].offset;
        const posefuse::sim::SensorKinematics motion(
            posefuse::sim::bvh_sensor_trajectory(clip, mount, 0.01, smoothing_s));
        posefuse::sim::ImuSynthOptions options;
        options.error_model = posefuse::sim::ImuErrorModel::none();
        // The motion's peaks, not a sensor's: no full-scale clipping.
        options.gyr_range_rad_s = options.acc_range_m_s2 = std::numeric_limits<double>::infinity();
        const auto imu = posefuse::sim::synthesize_imu(
            motion, posefuse::sim::uniform_times(motion.t_begin_s(), motion.t_end_s(), 80.0), options);
        imu_ms = wall_ms_since(start);
        for (const auto& sample : imu.samples) {
          max_rate = std::max(max_rate, sample.gyr_rad_s.norm());
          max_force = std::max(max_force, sample.acc_m_s2.norm());
        }
      }
      std::printf("%-22s %6zu %7d %7.1f %9.2f %9.2f %12.2f %12.2f %12.3f %12.2f %8.2f %8.2f\n",
                  path.filename().string().c_str(), clip.skeleton.joints.size(), clip.frame_count(),
                  1.0 / clip.frame_time_s, clip.duration_s(), parse_ms, fk_ms, resample_ms, head_above_hips_m, imu_ms,
                  max_rate, max_force);
      if (resampled.frames.empty()) ++failures;
    } catch (const posefuse::Error& e) {
      std::printf("%-22s error: %s\n", path.filename().string().c_str(), e.what());
      ++failures;
    }
  }
  return failures == 0 ? 0 : 1;
}
