#include "sim/body_imu.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "body/body_evaluator.hpp"
#include "body/template_generator.hpp"
#include "common/error.hpp"
#include "sim/bvh_motion.hpp"
#include "sim/exercises.hpp"
#include "sim/imu_synth.hpp"
#include "sim/room_frame.hpp"
#include "sim/skeleton_pose.hpp"
#include "test_motion.hpp"
#include "test_rigs.hpp"

using posefuse::Error;
using namespace posefuse::sim;
namespace body = posefuse::body;
using posefuse::sim::testing::integrate_gyro;

namespace {

using std::numbers::pi;

const Eigen::Matrix3Xd& rest_joints() {
  static const Eigen::Matrix3Xd rest = template_rest_joints(body::Sex::kMale, Eigen::VectorXd::Zero(10));
  return rest;
}

ImuSynthResult ideal_imu(const SensorKinematics& motion, double rate_hz = 80.0) {
  ImuSynthOptions options;
  options.error_model = ImuErrorModel::none();
  return synthesize_imu(motion, uniform_times(motion.t_begin_s(), motion.t_end_s(), rate_hz), options);
}

double largest_acceleration(const ImuSynthResult& imu) {
  double largest = 0.0;
  for (std::size_t k = 0; k < imu.samples.size(); ++k) {
    // Specific force minus gravity, in W: the acceleration of the sensor.
    const Vec3 a = imu.W_from_A[k] * imu.samples[k].acc_m_s2 - Vec3(0, 0, 9.81);
    largest = std::max(largest, a.norm());
  }
  return largest;
}

}  // namespace

TEST(BodyImu, SkeletonPoseMatchesTheBodyEvaluator) {
  const body::PoseLayout layout = body::PoseLayout::all_joints();
  body::BodyEvaluator evaluator(body::make_template(body::Sex::kFemale), layout);
  Eigen::VectorXd betas = Eigen::VectorXd::Zero(10);
  betas[0] = 1.0;
  betas[3] = -0.5;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> angle(-1.0, 1.0);
  Eigen::VectorXd theta(layout.size());
  for (int d = 0; d < layout.size(); ++d) theta[d] = angle(rng);
  evaluator.evaluate(betas, theta, body::Derivatives::kNone);
  const SkeletonPose pose = pose_skeleton(template_rest_joints(body::Sex::kFemale, betas), layout, theta);
  EXPECT_LT((pose.joints - evaluator.joints()).cwiseAbs().maxCoeff(), 1e-12);
  for (int j = 0; j < body::kNumJoints; ++j) {
    EXPECT_LT((pose.rotation[static_cast<std::size_t>(j)] - evaluator.joint_rotation(j)).cwiseAbs().maxCoeff(), 1e-12);
  }
  EXPECT_THROW(pose_skeleton(Eigen::Matrix3Xd::Zero(3, 5), layout, theta), Error);
  EXPECT_THROW(pose_skeleton(rest_joints(), layout, Eigen::VectorXd::Zero(4)), Error);
}

TEST(BodyImu, RoomFrameInTheWorld) {
  const Quat north = W_from_R(0.0);
  EXPECT_LT((north * Vec3::UnitY() - Vec3::UnitZ()).norm(), 1e-12);             // up is up
  EXPECT_LT((north * Vec3::UnitZ() - Vec3::UnitX()).norm(), 1e-12);             // front faces north
  EXPECT_LT((north * Vec3::UnitX() - Vec3::UnitY()).norm(), 1e-12);             // left is west
  EXPECT_LT((W_from_R(pi / 2) * Vec3::UnitZ() - Vec3::UnitY()).norm(), 1e-12);  // turned to the west
  EXPECT_THROW(W_from_R(std::nan("")), Error);
}

// The IMU strapped on the body during paper 1's protocol: gyro integrated from the first true
// orientation returns the last one, ideal and with gyro noise (within 5 sigma of the angle
// random walk); the accelerometer reads g at rest and physiological values in motion.
TEST(BodyImu, GyroFromTheBodyIntegratesBackToTheTruth) {
  ExerciseOptions options;
  options.repetitions = 1;
  const BodyMotion motion = make_exercise("forearm_protocol", options);
  ForearmStrap strap;
  strap.F_from_A = Quat(Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized()));
  const SensorKinematics kinematics(forearm_imu_trajectory(motion, rest_joints(), strap, W_from_R(0.4)));
  EXPECT_NEAR(kinematics.t_begin_s(), 0.0, 1e-12);
  EXPECT_NEAR(kinematics.t_end_s(), motion.duration_s, 1e-9);
  const ImuSynthResult ideal = ideal_imu(kinematics);
  const Quat end = integrate_gyro(ideal.samples, ideal.W_from_A.front());
  const double ideal_error_deg = posefuse::geometry::angle_between(end, ideal.W_from_A.back()) * 180 / pi;
  EXPECT_LT(ideal_error_deg, 0.01);
  EXPECT_NEAR(ideal.samples.front().acc_m_s2.norm(), 9.81, 1e-6);
  const double largest = largest_acceleration(ideal);
  EXPECT_GT(largest, 0.5);
  EXPECT_LT(largest, 20.0);

  const double T = motion.duration_s;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    ImuSynthOptions noisy;
    noisy.error_model = ImuErrorModel::none();
    noisy.error_model.gyr_noise_density_rad_s_sqrt_hz = ImuErrorModel{}.gyr_noise_density_rad_s_sqrt_hz;
    noisy.seed = seed;
    const ImuSynthResult imu =
        synthesize_imu(kinematics, uniform_times(kinematics.t_begin_s(), kinematics.t_end_s(), 80.0), noisy);
    const Quat q = integrate_gyro(imu.samples, imu.W_from_A.front());
    const double sigma_rad = noisy.error_model.gyr_noise_density_rad_s_sqrt_hz * std::sqrt(T) * std::sqrt(3.0);
    EXPECT_LT(posefuse::geometry::angle_between(q, imu.W_from_A.back()), 5 * sigma_rad) << seed;
  }
}

TEST(BodyImu, EveryExerciseGivesPhysiologicalSpecificForce) {
  for (const std::string& name : exercise_names()) {
    ExerciseOptions options;
    options.repetitions = 1;
    const BodyMotion motion = make_exercise(name, options);
    for (BodySide side : {BodySide::kRight, BodySide::kLeft}) {
      ForearmStrap strap;
      strap.side = side;
      const ImuSynthResult imu =
          ideal_imu(SensorKinematics(forearm_imu_trajectory(motion, rest_joints(), strap, W_from_R())));
      EXPECT_LT(largest_acceleration(imu), 25.0) << name;
      for (const auto& s : imu.samples) EXPECT_LT(s.gyr_rad_s.norm(), 12.0) << name;
    }
  }
}

// A mocap-like clip (60 fps, smooth arm swings plus 0.15 deg of noise on every rotation channel
// and 1 mm on the root: about 4 mm of jitter at the wrist, as optical mocap has): differentiated twice without
// smoothing it gives accelerations far beyond a real forearm's; bvh_motion's default smoothing brings them back to the
// noise-free motion's range.
TEST(BodyImu, MocapNoiseIsSmoothedBeforeDifferentiation) {
  const auto rig = posefuse::sim::testing::rig21();
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 1.0);
  const int frames = 600;
  std::vector<double> jitter(static_cast<std::size_t>(frames) * rig.size() * 6);
  for (double& v : jitter) v = noise(rng);
  auto clip_text = [&](double noise_scale) {
    return posefuse::sim::testing::rig_text(rig, frames, 1.0 / 60, [&](int f, int j, int c) {
      const double t = f / 60.0;
      const double n =
          noise_scale * jitter[(static_cast<std::size_t>(f) * rig.size() + static_cast<std::size_t>(j)) * 6 +
                               static_cast<std::size_t>(c)];
      if (rig[static_cast<std::size_t>(j)].root) return c < 3 ? (c == 1 ? 95.0 : 0.0) + 0.1 * n : 0.15 * n;
      double value = 0.15 * n;
      if (rig[static_cast<std::size_t>(j)].name == "RightArm" && c == 0) value += 60.0 * std::sin(2 * pi * 0.5 * t);
      if (rig[static_cast<std::size_t>(j)].name == "RightForeArm" && c == 1)
        value += 50.0 + 40.0 * std::sin(2 * pi * 0.8 * t);
      if (rig[static_cast<std::size_t>(j)].name == "RightForeArm" && c == 2) value += 60.0 * std::sin(2 * pi * 0.6 * t);
      return value;
    });
  };
  const BvhClip clean = parse_bvh(clip_text(0.0)), noisy = parse_bvh(clip_text(1.0));
  auto peak = [&](const BvhClip& clip, double smoothing_s) {
    BvhMotionOptions options;
    options.smoothing_s = smoothing_s;
    const SensorTrajectory trajectory =
        forearm_imu_trajectory(bvh_motion(clip, options), rest_joints(), ForearmStrap{}, W_from_R());
    return largest_acceleration(ideal_imu(SensorKinematics(trajectory)));
  };
  const double standard = BvhMotionOptions{}.smoothing_s;
  const double clean_peak = peak(clean, standard), raw_peak = peak(noisy, 0.0), smoothed_peak = peak(noisy, standard);
  std::printf("peak |a| m/s^2: clean %.1f, noisy unsmoothed %.1f, noisy smoothed %.2f s %.1f\n", clean_peak, raw_peak,
              standard, smoothed_peak);
  // Measured with the default 0.03 s: clean 8.3, unsmoothed 228.4 (per axis clipped at the
  // accelerometer's 16 g), smoothed 9.8 m/s^2 (0.02 s
  // leaves 20.5, 0.04 s 8.4).
  EXPECT_GT(raw_peak, 5.0 * clean_peak);
  EXPECT_LT(smoothed_peak, 1.3 * clean_peak);
  // Smoothing chosen from each channel's noise level instead of a fixed width.
  BvhMotionOptions by_noise;
  by_noise.smoothing = BvhSmoothing::kNoiseLevel;
  const double noise_level_peak = largest_acceleration(ideal_imu(SensorKinematics(
      forearm_imu_trajectory(bvh_motion(noisy, by_noise), rest_joints(), ForearmStrap{}, W_from_R()))));
  std::printf("noise-level smoothing spline: peak %.1f m/s^2\n", noise_level_peak);
  EXPECT_LT(noise_level_peak, 1.3 * clean_peak);
}

TEST(BodyImu, BaseImuOnTheCameraIsStill) {
  const Eigen::Isometry3d K_from_R =
      Eigen::Translation3d(0, -1.0, 2.5) * Eigen::AngleAxisd(pi, Eigen::Vector3d::UnitY());
  const BaseImuMount mount;
  const SensorKinematics base(base_imu_trajectory(K_from_R, W_from_R(0.3), mount, 0.0, 5.0));
  EXPECT_LE(base.t_begin_s(), 0.0);
  EXPECT_GE(base.t_end_s(), 5.0);
  const ImuSynthResult imu = ideal_imu(base);
  for (const auto& s : imu.samples) {
    EXPECT_LT(s.gyr_rad_s.norm(), 1e-12);
    EXPECT_LT((s.acc_m_s2 - Vec3(0, 9.81, 0)).norm(), 1e-9);  // a level camera: K's y is up
  }
  // The camera 2.5 m in front of the subject, 1 m up (+ the mount), facing it.
  const Vec3 p_R = W_from_R(0.3).conjugate() * base.at(1.0).p_W_m;
  EXPECT_LT((p_R - Vec3(0, 1.08, 2.5)).norm(), 1e-12);
  EXPECT_THROW(base_imu_trajectory(K_from_R, W_from_R(), mount, 1.0, 0.0), Error);
}

TEST(BodyImu, RejectsBadInput) {
  const BodyMotion motion = make_exercise("arm_raising");
  ForearmStrap strap;
  strap.strap_radius_m = -0.01;
  EXPECT_THROW(forearm_imu_trajectory(motion, rest_joints(), strap, W_from_R()), Error);
  strap = {};
  strap.F_from_A = Quat(2, 0, 0, 0);
  EXPECT_THROW(forearm_imu_trajectory(motion, rest_joints(), strap, W_from_R()), Error);
  BodyMotion broken = motion;
  broken.poses = [](double) { return Eigen::VectorXd::Zero(3); };
  EXPECT_THROW(forearm_imu_trajectory(broken, rest_joints(), ForearmStrap{}, W_from_R()), Error);
  broken.poses = nullptr;
  EXPECT_THROW(forearm_imu_trajectory(broken, rest_joints(), ForearmStrap{}, W_from_R()), Error);
  EXPECT_THROW(forearm_imu_trajectory(motion, rest_joints(), ForearmStrap{}, W_from_R(), 0.0), Error);
}
