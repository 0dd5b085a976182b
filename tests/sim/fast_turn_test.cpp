// Fast turns: a forearm rolling at 15 and 40 rad/s in 60 fps mocap (14 and 38 degrees per
// frame) reaches the synthetic gyro at its analytic rate, and the rate stencil takes coarse
// steps of a fast turn without a per-step limit.
#include <gtest/gtest.h>

#include <unistd.h>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>

#include "common/error.hpp"
#include "sim/body_imu.hpp"
#include "sim/bvh.hpp"
#include "sim/bvh_glitches.hpp"
#include "sim/bvh_motion.hpp"
#include "sim/imu_synth.hpp"
#include "sim/motion_library.hpp"
#include "sim/room_frame.hpp"
#include "test_motion.hpp"
#include "test_rigs.hpp"

using namespace posefuse;
using namespace posefuse::sim;
using std::numbers::pi;

namespace rigs = posefuse::sim::testing;

namespace {

// The 21-joint rig in its T-pose, the right forearm rolling about its bone (x) at rate_rad_s.
BvhClip rolling_forearm_clip(double rate_rad_s, double seconds) {
  const auto rig = rigs::rig21();
  const int frames = static_cast<int>(std::lround(seconds * 60)) + 1;
  return parse_bvh(rigs::rig_text(rig, frames, 1.0 / 60, [&](int f, int j, int c) {
    const auto& joint = rig[static_cast<std::size_t>(j)];
    if (joint.root) return c == 1 ? 95.0 : 0.0;
    if (joint.name == "RightForeArm" && c == 2) return rate_rad_s * (f / 60.0) * 180.0 / pi;
    return 0.0;
  }));
}

// Largest |gyr - analytic| over the middle of the clip (the natural spline's ends bend a constant
// rate), for an ideal IMU without saturation on the right forearm strap (F_from_A = I, so the
// roll is about A's y, the elbow -> wrist axis).
double worst_rate_error(const BodyMotion& motion, double rate_rad_s) {
  const Eigen::Matrix3Xd rest = template_rest_joints(body::Sex::kMale, Eigen::VectorXd::Zero(10));
  const SensorKinematics kinematics(forearm_imu_trajectory(motion, rest, ForearmStrap{}, W_from_R()));
  ImuSynthOptions options;
  options.error_model = ImuErrorModel::none();
  options.gyr_range_rad_s = std::numeric_limits<double>::infinity();
  const ImuSynthResult imu =
      synthesize_imu(kinematics, uniform_times(0.25 * motion.duration_s, 0.75 * motion.duration_s, 80.0), options);
  double worst = 0;
  for (const auto& s : imu.samples) {
    const double sign = s.gyr_rad_s.y() > 0 ? 1.0 : -1.0;
    worst = std::max(worst, (s.gyr_rad_s - sign * rate_rad_s * Vec3::UnitY()).norm());
  }
  return worst;
}

double worst_rate_error(double rate_rad_s) {
  const BvhClip clip = rolling_forearm_clip(rate_rad_s, 3.0);
  EXPECT_TRUE(repair_bvh_glitches(clip).glitches.empty()) << rate_rad_s << " rad/s is no glitch";
  return worst_rate_error(bvh_motion(clip), rate_rad_s);
}

}  // namespace

// The error bound: bvh_motion joins hemisphere-aligned quaternion components by a cubic spline;
// a constant-rate roll has components cos, sin(omega t / 2) (the default Gaussian smoothing
// scales all of them alike, which the normalisation undoes). A cubic spline's derivative is off
// by at most h^3 / 24 |f''''| per component (Hall and Meyer 1976), |f''''| = (omega / 2)^4, and
// the rate is 2 |q'|: with 4 components at most 4 h^3 (omega / 2)^4 / 24 * 2 = h^3 omega^4 / 96.
TEST(FastTurn, MocapRollAt15RadPerSecondReadsItsRate) {
  const double h = 1.0 / 60, omega = 15.0;
  const double bound = std::pow(h, 3) * std::pow(omega, 4) / 96;
  const double worst = worst_rate_error(omega);
  std::printf("15 rad/s: worst gyro error %.3g rad/s (bound %.3g)\n", worst, bound);
  EXPECT_LT(worst, bound);
}

TEST(FastTurn, MocapRollAt40RadPerSecondReadsItsRate) {
  const double h = 1.0 / 60, omega = 40.0;
  const double bound = std::pow(h, 3) * std::pow(omega, 4) / 96;
  const double worst = worst_rate_error(omega);
  std::printf("40 rad/s: worst gyro error %.3g rad/s (bound %.3g)\n", worst, bound);
  EXPECT_LT(worst, bound);
}

// posefuse-sim's path: the clip from a file through select_motion at speed 2 turns at twice the
// rate; time runs twice as fast through the same spline, so the bound doubles too.
TEST(FastTurn, SpeedTwoPlaysTheClipAtTwiceTheRate) {
  const auto rig = rigs::rig21();
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("posefuse_fast_turn_" + std::to_string(::getpid()) + ".bvh");
  {
    std::ofstream out(path);
    out << rigs::rig_text(rig, 181, 1.0 / 60, [&](int f, int j, int c) {
      const auto& joint = rig[static_cast<std::size_t>(j)];
      if (joint.root) return c == 1 ? 95.0 : 0.0;
      if (joint.name == "RightForeArm" && c == 2) return 15.0 * (f / 60.0) * 180.0 / pi;
      return 0.0;
    });
  }
  MotionOptions options;
  options.bvh_path = path.string();
  options.exercise.speed = 2.0;
  const BodyMotion motion = select_motion("bvh", options, MotionContext{});
  std::filesystem::remove(path);
  EXPECT_NEAR(motion.duration_s, 1.5, 1e-9);
  EXPECT_TRUE(motion.warnings.empty());
  const double h = 1.0 / 60, omega = 15.0;
  const double bound = 2.0 * std::pow(h, 3) * std::pow(omega, 4) / 96;
  const double worst = worst_rate_error(motion, 2.0 * omega);
  std::printf("speed 2: 30 rad/s read with worst error %.3g rad/s (bound %.3g)\n", worst, bound);
  EXPECT_LT(worst, bound);
}

// A constant rate about a fixed axis gives r_j = j omega dt exactly, so the 5-point stencil is
// exact at any step that log() reads unambiguously: 0.6 rad per step here.
TEST(FastTurn, CoarseGridOfAFastTurnIsExact) {
  const Vec3 axis = Vec3(1, 2, 2).normalized();
  const double omega = 60.0, dt = 0.01;
  const auto q = [&](double t) { return Quat(Eigen::AngleAxisd(omega * t, axis)); };
  const SensorKinematics kinematics(rigs::sample_trajectory([](double) { return Vec3::Zero(); }, q, 0.0, 1.0, dt));
  for (double t = kinematics.t_begin_s(); t <= kinematics.t_end_s(); t += 0.0037) {
    EXPECT_LT((kinematics.at(t).omega_A_rad_s - omega * axis).norm(), 1e-9) << t;
  }
}

TEST(FastTurn, AliasedTurnIsRefusedNamingThePose) {
  // 1.6 rad per step: 3.2 rad over the stencil's 2 steps reads as a turn the other way.
  const auto q = [](double t) { return Quat(Eigen::AngleAxisd(160.0 * t, Vec3::UnitZ())); };
  try {
    SensorKinematics(rigs::sample_trajectory([](double) { return Vec3::Zero(); }, q, 0.0, 0.1, 0.01));
    FAIL() << "an aliased turn was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "trajectory.W_from_A[2]");
    EXPECT_NE(std::string(e.what()).find("ambiguous"), std::string::npos) << e.what();
  }
}
