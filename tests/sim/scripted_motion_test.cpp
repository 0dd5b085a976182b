#include "sim/scripted_motion.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "common/error.hpp"
#include "sim/imu_synth.hpp"
#include "test_motion.hpp"

using posefuse::Error;
using posefuse::geometry::angle_between;
using namespace posefuse::sim;
using namespace posefuse::sim::testing;

namespace {

constexpr double kDeg = pi / 180.0;

void expect_near(const Vec3& a, const Vec3& b, double tol) {
  EXPECT_LT((a - b).norm(), tol) << "got " << a.transpose() << " want " << b.transpose();
}

ImuSynthOptions ideal_options() {
  ImuSynthOptions o;
  o.error_model = ImuErrorModel::none();
  return o;
}

}  // namespace

TEST(ArmPose, HangingArmAxes) {
  ArmGeometry g;
  const ArmPose p = arm_pose(g, ArmAngles());
  expect_near(p.W_from_F * Vec3::UnitY(), -Vec3::UnitZ(), 1e-12);  // elbow -> wrist: down
  expect_near(p.W_from_F * Vec3::UnitZ(), Vec3::UnitX(), 1e-12);   // thumb: forward
  expect_near(p.W_from_F * Vec3::UnitX(), -Vec3::UnitY(), 1e-12);  // back of the hand: right
  expect_near(p.elbow_p_W_m, g.shoulder_p_W_m - Vec3(0, 0, 0.30), 1e-12);
  expect_near(p.strap_p_W_m, g.shoulder_p_W_m - Vec3(0, 0, 0.50), 1e-12);
  expect_near(p.imu_p_W_m, p.strap_p_W_m + Vec3(0, -0.035, 0), 1e-12);
}

// Paper 1, Fig. 3b: upper arm sideways and horizontal, forearm up, palm to the camera (in
// front of the subject), both in the coronal plane.
TEST(ArmPose, CalibrationPoseMatchesPaper) {
  ArmGeometry g;
  g.heading_rad = 0.7;  // the subject faces W's x turned by 0.7 rad
  const Vec3 forward(std::cos(0.7), std::sin(0.7), 0);
  const Vec3 left(-std::sin(0.7), std::cos(0.7), 0);
  const ArmPose p = arm_pose(g, calibration_pose_angles());
  expect_near(p.elbow_p_W_m, g.shoulder_p_W_m - 0.30 * left, 1e-12);
  expect_near(p.W_from_F * Vec3::UnitY(), Vec3::UnitZ(), 1e-12);          // forearm up
  expect_near(p.W_from_F * Vec3::UnitX(), -forward, 1e-12);               // back of the hand away from the camera
  expect_near(p.W_from_F * Vec3::UnitZ(), left, 1e-12);                   // thumb towards the head
  EXPECT_NEAR((p.strap_p_W_m - p.elbow_p_W_m).dot(forward), 0.0, 1e-12);  // coronal plane
}

TEST(ArmPose, SupinationTurnsTheThumbOutwards) {
  ArmAngles a;
  a.elbow_flexion_rad = 90 * kDeg;  // forearm forward, thumb up
  const ArmPose neutral = arm_pose(ArmGeometry(), a);
  expect_near(neutral.W_from_F * Vec3::UnitY(), Vec3::UnitX(), 1e-12);
  expect_near(neutral.W_from_F * Vec3::UnitZ(), Vec3::UnitZ(), 1e-12);
  a.supination_rad = 90 * kDeg;
  const ArmPose supinated = arm_pose(ArmGeometry(), a);
  expect_near(supinated.W_from_F * Vec3::UnitZ(), -Vec3::UnitY(), 1e-12);  // right arm: outwards
  expect_near(supinated.W_from_F * Vec3::UnitX(), -Vec3::UnitZ(), 1e-12);  // back of the hand down: palm up
}

TEST(ScriptedMotion, ForearmRollingRotatesAboutTheForearmOnly) {
  ForearmRollingOptions o;
  o.repetitions = 3;
  const ScriptedMotion m = forearm_rolling(o);
  EXPECT_DOUBLE_EQ(m.duration_s, 2 * 1.0 + 3 * 2.0);
  ArmGeometry g;
  g.F_from_A = rot(0.3, Vec3(1, 1, 0).normalized());  // a tilted IMU
  const ArmPose start = arm_pose(g, m.angles(0.0));
  double peak = 0;
  for (double t = 0; t <= m.duration_s; t += 0.01) {
    const ArmAngles a = m.angles(t);
    peak = std::max(peak, std::abs(a.supination_rad));
    const ArmPose p = arm_pose(g, a);
    expect_near(p.W_from_F * Vec3::UnitY(), start.W_from_F * Vec3::UnitY(), 1e-12);  // axis fixed
    expect_near(p.strap_p_W_m, start.strap_p_W_m, 1e-12);
    EXPECT_NEAR((p.imu_p_W_m - p.strap_p_W_m).norm(), g.strap_radius_m, 1e-12);
    // 1e-7: angle_between uses acos, which resolves small angles to about sqrt(eps).
    EXPECT_NEAR(angle_between(p.W_from_F, start.W_from_F), std::abs(a.supination_rad), 1e-7);
  }
  EXPECT_NEAR(peak, o.amplitude_rad, 1e-3);
  EXPECT_EQ(m.angles(0.5).supination_rad, 0.0);  // hold
  EXPECT_EQ(m.angles(m.duration_s - 0.5).supination_rad, 0.0);

  // The IMU pipeline on it: the synthesized gyro integrates back to the truth, and it turns
  // about the forearm axis expressed in A.
  const SensorKinematics motion(imu_trajectory(g, m));
  EXPECT_NEAR(motion.t_begin_s(), 0.0, 1e-12);
  EXPECT_NEAR(motion.t_end_s(), m.duration_s, 1e-9);
  const ImuSynthResult r = synthesize_imu(motion, uniform_times(0.0, m.duration_s, 80), ideal_options());
  const Quat end = integrate_gyro(r.samples, arm_pose(g, m.angles(0)).W_from_A);
  EXPECT_LT(angle_between(end, arm_pose(g, m.angles(r.samples.back().t_us * 1e-6)).W_from_A), 0.01 * kDeg);
  const Vec3 axis_A = g.F_from_A.conjugate() * Vec3::UnitY();
  for (const auto& s : r.samples) EXPECT_LT(s.gyr_rad_s.cross(axis_A).norm(), 1e-6);
}

TEST(ScriptedMotion, ArmRaisingReachesPeakAndReturns) {
  for (auto plane : {ArmRaisingOptions::Plane::kFrontal, ArmRaisingOptions::Plane::kSagittal}) {
    ArmRaisingOptions o;
    o.plane = plane;
    o.repetitions = 2;
    const ScriptedMotion m = arm_raising(o);
    EXPECT_DOUBLE_EQ(m.duration_s, 2 * 1.0 + 2 * 5.0 - 0.5);
    const ArmGeometry g;
    const Vec3 down = -Vec3::UnitZ();
    double peak = 0;
    for (double t = 0; t <= m.duration_s; t += 0.01) {
      const ArmPose p = arm_pose(g, m.angles(t));
      peak = std::max(peak, std::acos(std::clamp((p.W_from_F * Vec3::UnitY()).dot(down), -1.0, 1.0)));
      // The elbow stays straight: elbow and strap on one line from the shoulder.
      EXPECT_NEAR((p.strap_p_W_m - g.shoulder_p_W_m).norm(), 0.50, 1e-12);
    }
    EXPECT_NEAR(peak, o.peak_rad, 1e-3);
    // At the top of the first repetition (t = 1 + 2 + 0.25 s) the hand points up-and-out/forward.
    const ArmPose top = arm_pose(g, m.angles(3.25));
    const Vec3 sideways = plane == ArmRaisingOptions::Plane::kFrontal ? Vec3(-Vec3::UnitY()) : Vec3(Vec3::UnitX());
    EXPECT_GT((top.W_from_F * Vec3::UnitY()).dot(sideways), 0.4);
    EXPECT_GT((top.W_from_F * Vec3::UnitY()).dot(Vec3::UnitZ()), 0.8);
    // Back to hanging at the end, at rest.
    expect_near(arm_pose(g, m.angles(m.duration_s)).W_from_F * Vec3::UnitY(), down, 1e-12);
    const SensorKinematics motion(imu_trajectory(g, m));
    EXPECT_LT(motion.at(0.0).omega_A_rad_s.norm(), 1e-9);
    EXPECT_LT(motion.at(m.duration_s).omega_A_rad_s.norm(), 1e-9);
  }
}

TEST(ScriptedMotion, CalibrationHoldIsStill) {
  const ScriptedMotion m = calibration_hold(CalibrationHoldOptions());
  const SensorKinematics motion(imu_trajectory(ArmGeometry(), m));
  const ImuSynthResult r = synthesize_imu(motion, uniform_times(0.0, m.duration_s, 80), ideal_options());
  for (const auto& s : r.samples) {
    EXPECT_LT(s.gyr_rad_s.norm(), 1e-9);
    EXPECT_NEAR(s.acc_m_s2.norm(), 9.81, 1e-6);
  }
  // With sway the pose moves a little but stays near the calibration pose.
  CalibrationHoldOptions sway;
  sway.sway_rad = 1.0 * kDeg;
  const ScriptedMotion swaying = calibration_hold(sway);
  const ArmPose ref = arm_pose(ArmGeometry(), calibration_pose_angles());
  double max_angle = 0;
  for (double t = 0; t <= swaying.duration_s; t += 0.01) {
    max_angle = std::max(max_angle, angle_between(arm_pose(ArmGeometry(), swaying.angles(t)).W_from_F, ref.W_from_F));
  }
  EXPECT_GT(max_angle, 0.5 * kDeg);
  EXPECT_LT(max_angle, 5.0 * kDeg);
}

TEST(ScriptedMotion, RejectsBadOptions) {
  ForearmRollingOptions rolling;
  rolling.period_s = 0;
  EXPECT_THROW(forearm_rolling(rolling), Error);
  rolling = ForearmRollingOptions();
  rolling.repetitions = 0;
  EXPECT_THROW(forearm_rolling(rolling), Error);
  ArmRaisingOptions raising;
  raising.raise_s = -1;
  EXPECT_THROW(arm_raising(raising), Error);
  CalibrationHoldOptions hold;
  hold.duration_s = std::nan("");
  EXPECT_THROW(calibration_hold(hold), Error);
  ArmGeometry g;
  g.upper_arm_m = 0;
  EXPECT_THROW(imu_trajectory(g, calibration_hold(CalibrationHoldOptions())), Error);
  EXPECT_THROW(imu_trajectory(ArmGeometry(), ScriptedMotion()), Error);
}
