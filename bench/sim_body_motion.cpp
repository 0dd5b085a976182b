// The body-driven simulator on the shared mocap clips and the scripted exercises.
//
// Per clip: retargeting onto the template (thread CPU ms for bvh_motion, all frames), the
// bone-direction error of the retargeted model against the BVH at every frame (mean and max
// degrees over all mapped bones; without smoothing it is the retargeting error alone, with the
// default 0.03 s smoothing it includes the smoothing), and the right forearm IMU driven by the
// body (paper 1 strap, d_se 0.18 m, r 3.5 cm): largest |angular rate| (rad/s) and |acceleration|
// (specific force minus g, m/s^2, without full-scale clipping) for smoothing 0, 0.03 (default) and 0.05 s
// and for the noise-level smoothing spline (BvhSmoothing::kNoiseLevel). Then per exercise: duration,
// IMU trajectory time and the same peaks.
//
//   build/bench/bench_sim_body_motion [folder=../shared/data/mocap]
//
// The clips are not part of the repository: when the folder is missing, the clip part says so
// and is skipped.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "bench_clock.hpp"
#include "common/error.hpp"
#include "sim/body_imu.hpp"
#include "sim/bvh_motion.hpp"
#include "sim/bvh_retarget.hpp"
#include "sim/exercises.hpp"
#include "sim/imu_synth.hpp"
#include "sim/room_frame.hpp"
#include "sim/skeleton_pose.hpp"

namespace {

using namespace posefuse::sim;
namespace body = posefuse::body;
using posefuse::bench::thread_cpu_seconds;

struct Peaks {
  double gyr = 0.0, acc = 0.0, ms = 0.0;
};

Peaks imu_peaks(const BodyMotion& motion, const Eigen::Matrix3Xd& rest) {
  const double start = thread_cpu_seconds();
  const SensorKinematics kinematics(forearm_imu_trajectory(motion, rest, ForearmStrap{}, W_from_R()));
  ImuSynthOptions options;
  options.error_model = ImuErrorModel::none();
  // The motion's peaks, not a sensor's: no full-scale clipping.
  options.gyr_range_rad_s = options.acc_range_m_s2 = std::numeric_limits<double>::infinity();
  const ImuSynthResult imu =
      synthesize_imu(kinematics, uniform_times(kinematics.t_begin_s(), kinematics.t_end_s(), 80.0), options);
  Peaks p;
  p.ms = 1e3 * (thread_cpu_seconds() - start);
  for (std::size_t k = 0; k < imu.samples.size(); ++k) {
    p.gyr = std::max(p.gyr, imu.samples[k].gyr_rad_s.norm());
    p.acc = std::max(p.acc, (imu.W_from_A[k] * imu.samples[k].acc_m_s2 - Vec3(0, 0, 9.81)).norm());
  }
  return p;
}

// Mean and max angle (degrees) between the model's mapped bones and the BVH's at every frame.
void bone_errors(const BvhClip& clip, const BodyMotion& motion, const BvhPlacement& place, const Eigen::Matrix3Xd& rest,
                 double& mean_deg, double& max_deg) {
  const BvhRetargetMap map = make_bvh_retarget_map(clip.skeleton, rest);
  double sum = 0.0;
  int count = 0;
  max_deg = 0.0;
  for (int f = 0; f < clip.frame_count(); ++f) {
    const SkeletonPose pose = pose_skeleton(rest, body::PoseLayout::all_joints(), motion.poses(f * clip.frame_time_s));
    const std::vector<Vec3> p = bvh_joint_positions(clip.skeleton, clip.frames[static_cast<std::size_t>(f)]);
    for (int j = 0; j < body::kNumJoints; ++j) {
      const int c = map.aim_joint[static_cast<std::size_t>(j)];
      if (c < 0) continue;
      const Vec3 model = pose.joints.col(c) - pose.joints.col(j);
      const Vec3 bvh = place.R_from_bvh * (p[static_cast<std::size_t>(map.bvh_joint[static_cast<std::size_t>(c)])] -
                                           p[static_cast<std::size_t>(map.bvh_joint[static_cast<std::size_t>(j)])]);
      const double deg = std::atan2(model.cross(bvh).norm(), model.dot(bvh)) * 180.0 / 3.14159265358979323846;
      sum += deg;
      max_deg = std::max(max_deg, deg);
      ++count;
    }
  }
  mean_deg = count > 0 ? sum / count : 0.0;
}

}  // namespace

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  const fs::path folder = argc > 1 ? fs::path(argv[1]) : fs::path("../shared/data/mocap");
  const Eigen::Matrix3Xd rest = template_rest_joints(body::Sex::kMale, Eigen::VectorXd::Zero(body::kTemplateNumBetas));
  int failures = 0;
  if (!fs::is_directory(folder)) {
    std::printf("bench_sim_body_motion: %s not found, skipping the clips\n", folder.string().c_str());
  } else {
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(folder)) {
      if (entry.is_regular_file() && entry.path().extension() == ".bvh") files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    std::printf("%-18s %7s %10s %17s %17s %13s %13s %13s %17s %13s\n", "clip", "frames", "retarget_ms",
                "bone_err_s0 mean/max", "bone_err_s.03 mean/max", "gyr/acc s0", "gyr/acc s.03", "gyr/acc s.05",
                "bone_err_noise mean/max", "gyr/acc noise");
    for (const fs::path& path : files) {
      try {
        const BvhClip clip = load_bvh(path);
        double mean0 = 0, max0 = 0, mean2 = 0, max2 = 0, mean_noise = 0, max_noise = 0;
        Peaks peaks[4];
        double retarget_ms = 0.0;
        const double smoothing[3] = {0.0, BvhMotionOptions{}.smoothing_s, 0.05};
        for (int s = 0; s < 3; ++s) {
          BvhMotionOptions options;
          options.smoothing_s = smoothing[s];
          BvhPlacement place;
          const double start = thread_cpu_seconds();
          const BodyMotion motion = bvh_motion(clip, options, &place);
          if (s == 1) retarget_ms = 1e3 * (thread_cpu_seconds() - start);
          if (s == 0) bone_errors(clip, motion, place, rest, mean0, max0);
          if (s == 1) bone_errors(clip, motion, place, rest, mean2, max2);
          peaks[s] = imu_peaks(motion, rest);
        }
        BvhMotionOptions by_noise;
        by_noise.smoothing = BvhSmoothing::kNoiseLevel;
        BvhPlacement place;
        const BodyMotion motion = bvh_motion(clip, by_noise, &place);
        bone_errors(clip, motion, place, rest, mean_noise, max_noise);
        peaks[3] = imu_peaks(motion, rest);
        std::printf(
            "%-18s %7d %10.1f %8.4f/%8.4f %8.2f/%8.2f %6.1f/%6.1f %6.1f/%6.1f %6.1f/%6.1f %8.2f/%8.2f %6.1f/%6.1f\n",
            path.filename().string().c_str(), clip.frame_count(), retarget_ms, mean0, max0, mean2, max2, peaks[0].gyr,
            peaks[0].acc, peaks[1].gyr, peaks[1].acc, peaks[2].gyr, peaks[2].acc, mean_noise, max_noise, peaks[3].gyr,
            peaks[3].acc);
      } catch (const posefuse::Error& e) {
        std::printf("%-18s error: %s\n", path.filename().string().c_str(), e.what());
        ++failures;
      }
    }
  }
  std::printf("\n%-26s %10s %16s %10s %10s\n", "exercise (right arm)", "duration_s", "imu_trajectory_ms", "max_gyr",
              "max_acc");
  for (const std::string& name : exercise_names()) {
    const BodyMotion motion = make_exercise(name);
    const Peaks p = imu_peaks(motion, rest);
    std::printf("%-26s %10.1f %16.1f %10.2f %10.2f\n", name.c_str(), motion.duration_s, p.ms, p.gyr, p.acc);
  }
  return failures == 0 ? 0 : 1;
}
