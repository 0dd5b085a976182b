// The arm IMU's mounting from natural motion and the confidence of an orientation.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "forearm/mounting_from_motion.hpp"
#include "forearm/orientation_uncertainty.hpp"
#include "geometry/quaternion.hpp"

namespace posefuse::forearm {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

Quat rot(double angle, const Vec3& axis) { return Quat(Eigen::AngleAxisd(angle, axis.normalized())); }

double angle_between(const Quat& a, const Quat& b) { return a.angularDistance(b); }

// A forearm in K at time i: neutral frame N turning through varied directions, pronation
// (twist about y) tau, the upper arm in N's y-z plane flexed by `flexion`.
struct ArmAt {
  Quat K_from_F;
  Vec3 forearm_K;
  Vec3 upper_arm_K;
};

ArmAt arm_at(int i, Side side, double tau, double flexion) {
  const double t = 0.033 * i;
  const Quat K_from_N = rot(0.9 * std::sin(0.31 * t), Vec3(1, 0.2, 0)) *
                        rot(1.2 * std::sin(0.23 * t + 1), Vec3(0, 1, 0.3)) *
                        rot(0.6 * std::cos(0.17 * t), Vec3(0, 0, 1));
  const double s = side == Side::kRight ? 1.0 : -1.0;
  const Vec3 upper_N(0, std::cos(flexion), -s * std::sin(flexion));
  return {K_from_N * rot(tau, Vec3::UnitY()), K_from_N * Vec3::UnitY(), K_from_N * upper_N};
}

std::vector<MountingFrame> frames_of(Side side, const Quat& F_from_A, int count, double twist_amplitude, double flexion,
                                     double noise_rad = 0.0, unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, noise_rad > 0 ? noise_rad : 1.0);  // drawn only with noise
  std::vector<MountingFrame> frames;
  for (int i = 0; i < count; ++i) {
    const double tau = twist_amplitude * std::sin(2 * kPi * i / 150.0);
    const ArmAt arm = arm_at(i, side, tau, flexion);
    MountingFrame f;
    f.t_us = 33'333LL * i;
    f.K_from_A = arm.K_from_F * F_from_A;
    f.forearm_K = arm.forearm_K;
    if (noise_rad > 0) {
      const Vec3 v(normal(rng), normal(rng), normal(rng));
      f.forearm_K = geometry::quat_from_rotation_vector(v) * arm.forearm_K;
    }
    f.upper_arm_K = arm.upper_arm_K;
    frames.push_back(f);
  }
  return frames;
}

TEST(MountingFromMotion, NeutralFrameIsTheCalibrationPoseFrame) {
  // Paper 1 Fig. 3b facing the camera (K: x to the camera's left, y up, z away from the camera):
  // the subject's right upper arm points to the camera's left, the forearm up.
  const Vec3 shoulder(0.2, 0.3, 2.0), elbow(0.45, 0.3, 2.0), wrist(0.45, 0.55, 2.0);
  const Quat pose = K_from_F_calibration_pose(shoulder, elbow, wrist);
  const std::optional<Quat> neutral = K_from_neutral_forearm(elbow - shoulder, wrist - elbow, Side::kRight, 30 * kDeg);
  ASSERT_TRUE(neutral);
  EXPECT_LT(angle_between(*neutral, pose), 1e-9);
  // The left arm mirrored: upper arm to the camera's right.
  const Vec3 l_shoulder(-0.2, 0.3, 2.0), l_elbow(-0.45, 0.3, 2.0), l_wrist(-0.45, 0.55, 2.0);
  const std::optional<Quat> left =
      K_from_neutral_forearm(l_elbow - l_shoulder, l_wrist - l_elbow, Side::kLeft, 30 * kDeg);
  ASSERT_TRUE(left);
  EXPECT_LT(angle_between(*left, K_from_F_calibration_pose(l_shoulder, l_elbow, l_wrist)), 1e-9);
  // A straight elbow has no hinge plane.
  EXPECT_FALSE(K_from_neutral_forearm(elbow - shoulder, elbow - shoulder, Side::kRight, 30 * kDeg));
  EXPECT_FALSE(K_from_neutral_forearm(Vec3(1, 0, 0), Vec3(1, 0.4, 0), Side::kRight, 30 * kDeg));  // 22 degrees
}

TEST(MountingFromMotion, KnownMountingFromAFullPronationSweep) {
  for (Side side : {Side::kRight, Side::kLeft}) {
    // 25 degrees of roll off the nominal mounting, and a tilt of the axis.
    const Quat F_from_A = rot(25 * kDeg, Vec3::UnitY()) * rot(8 * kDeg, Vec3(1, 0, 1));
    std::string why;
    const std::optional<MountingEstimate> e =
        estimate_mounting(frames_of(side, F_from_A, 600, 89.5 * kDeg, 80 * kDeg), side, {}, why);
    ASSERT_TRUE(e) << why;
    const Quat A_from_F = F_from_A.conjugate();
    const Vec3 true_axis = A_from_F * Vec3::UnitY(), axis = e->F_from_A.conjugate() * Vec3::UnitY();
    EXPECT_LT(std::acos(std::min(1.0, true_axis.dot(axis))), 1e-9);
    EXPECT_LT(e->axis_rms_rad, 1e-9);
    EXPECT_TRUE(e->roll_from_hinge) << e->roll_limit;
    EXPECT_EQ(e->hinge_frames, 600u);
    EXPECT_GT(e->twist_span_rad, 170 * kDeg);
    const double roll_error = angle_between(e->F_from_A, F_from_A);
    EXPECT_LT(roll_error, 5 * kDeg);
    EXPECT_LT(roll_error, 2.0 * e->roll_rms_rad);  // the predicted RMS covers it
    EXPECT_LT(e->roll_rms_rad, 6 * kDeg);
    EXPECT_NEAR(e->seconds, 599 * 0.033333, 1e-3);
    EXPECT_GT(e->axis_spread_rad, 20 * kDeg);
  }
}

TEST(MountingFromMotion, ASmallPronationRangeLeavesTheRollUncertain) {
  // The forearm turns +-20 degrees: the roll can be anywhere in a 140-degree interval.
  const Quat F_from_A = rot(10 * kDeg, Vec3::UnitY());
  std::string why;
  const std::optional<MountingEstimate> e =
      estimate_mounting(frames_of(Side::kRight, F_from_A, 300, 20 * kDeg, 60 * kDeg), Side::kRight, {}, why);
  ASSERT_TRUE(e) << why;
  EXPECT_TRUE(e->roll_from_hinge);
  EXPECT_GT(e->roll_rms_rad, 20 * kDeg);
  EXPECT_LT(confidence_from_rms_rad(orientation_rms_rad(e->axis_rms_rad, e->roll_rms_rad)), 0.01);
}

TEST(MountingFromMotion, NoElbowFlexionLeavesTheRollUnobservableAndSaysSo) {
  const Quat F_from_A = rot(-15 * kDeg, Vec3::UnitY()) * rot(5 * kDeg, Vec3::UnitX());
  std::string why;
  const std::optional<MountingEstimate> e =
      estimate_mounting(frames_of(Side::kLeft, F_from_A, 200, 60 * kDeg, 10 * kDeg), Side::kLeft, {}, why);
  ASSERT_TRUE(e) << why;
  EXPECT_FALSE(e->roll_from_hinge);
  EXPECT_EQ(e->hinge_frames, 0u);
  EXPECT_NE(e->roll_limit.find("no frame with the elbow flexed"), std::string::npos) << e->roll_limit;
  EXPECT_DOUBLE_EQ(e->roll_rms_rad, 30 * kDeg);
  // The axis is still exact; the roll is the nominal mounting's (A along F).
  const Vec3 true_axis = F_from_A.conjugate() * Vec3::UnitY(), axis = e->F_from_A.conjugate() * Vec3::UnitY();
  EXPECT_LT(std::acos(std::min(1.0, true_axis.dot(axis))), 1e-9);
  EXPECT_LT(e->F_from_A.angularDistance(Quat::Identity()), 6 * kDeg);
}

TEST(MountingFromMotion, ATwistBeyondWhatAForearmCanTurnIsNamed) {
  // The IMU rolls 130 degrees each way against the hinge: a slipping strap, not a forearm.
  std::string why;
  const std::optional<MountingEstimate> e =
      estimate_mounting(frames_of(Side::kRight, Quat::Identity(), 300, 130 * kDeg, 70 * kDeg), Side::kRight, {}, why);
  ASSERT_TRUE(e) << why;
  EXPECT_FALSE(e->roll_from_hinge);
  EXPECT_NE(e->roll_limit.find("more than a forearm can"), std::string::npos) << e->roll_limit;
  EXPECT_DOUBLE_EQ(e->roll_rms_rad, 30 * kDeg);
}

TEST(MountingFromMotion, AnImuThatDoesNotTurnWithTheForearmIsRefused) {
  std::vector<MountingFrame> frames = frames_of(Side::kRight, Quat::Identity(), 300, 30 * kDeg, 60 * kDeg);
  for (MountingFrame& f : frames) f.K_from_A = Quat::Identity();  // an IMU lying still on the table
  std::string why;
  EXPECT_FALSE(estimate_mounting(frames, Side::kRight, {}, why));
  EXPECT_NE(why.find("scatter"), std::string::npos) << why;
}

TEST(MountingFromMotion, AnImuOnTheOtherArmIsNamed) {
  // The left forearm moves as the right one mirrored left-right; the IMU named for the left arm is
  // strapped to the right one.
  const Quat F_from_A = rot(10 * kDeg, Vec3::UnitY());
  const std::vector<MountingFrame> right = frames_of(Side::kRight, F_from_A, 300, 40 * kDeg, 60 * kDeg, 3 * kDeg);
  std::vector<MountingFrame> left = right;
  for (MountingFrame& f : left) f.forearm_K.x() = -f.forearm_K.x();
  // With the IMU on the right forearm: the left forearm's axes scatter in its frame, the right's do not.
  const std::optional<std::string> named = imu_on_other_arm(left, right, {});
  ASSERT_TRUE(named);
  EXPECT_NE(named->find("the IMU turns with the other arm"), std::string::npos) << *named;
  // Named for the arm it is on: nothing to say.
  EXPECT_FALSE(imu_on_other_arm(right, left, {}));
  // Both forearms the same (parallel arms): the other arm explains the IMU no better.
  EXPECT_FALSE(imu_on_other_arm(right, right, {}));
  // Forearms that move alike, the IMU's own seen with more depth noise (beyond the 15 degree
  // bound) than the other: the difference is the noise's, not a mismatch.
  const std::vector<MountingFrame> noisy = frames_of(Side::kRight, F_from_A, 300, 40 * kDeg, 60 * kDeg, 12 * kDeg, 2);
  const std::vector<MountingFrame> cleaner = frames_of(Side::kRight, F_from_A, 300, 40 * kDeg, 60 * kDeg, 8 * kDeg, 3);
  EXPECT_FALSE(imu_on_other_arm(noisy, cleaner, {}));
  // Too few frames of the other arm to compare.
  EXPECT_FALSE(imu_on_other_arm(left, std::vector<MountingFrame>(right.begin(), right.begin() + 10), {}));
}

TEST(MountingFromMotion, AMinorityOfFramesWithAWrongForearmAxisIsLeftOut) {
  const Quat F_from_A = rot(10 * kDeg, Vec3::UnitY());
  std::vector<MountingFrame> frames = frames_of(Side::kRight, F_from_A, 300, 60 * kDeg, 70 * kDeg);
  // Every third frame's forearm axis 40 degrees off (foreshortened towards the camera).
  for (std::size_t i = 0; i < frames.size(); i += 3)
    frames[i].forearm_K = rot(40 * kDeg, Vec3::UnitX()) * frames[i].forearm_K;
  std::string why;
  const std::optional<MountingEstimate> e = estimate_mounting(frames, Side::kRight, {}, why);
  ASSERT_TRUE(e) << why;
  EXPECT_EQ(e->outlier_frames, 100u);
  EXPECT_EQ(e->frames, 200u);
  const Vec3 true_axis = F_from_A.conjugate() * Vec3::UnitY(), axis = e->F_from_A.conjugate() * Vec3::UnitY();
  EXPECT_LT(std::acos(std::min(1.0, true_axis.dot(axis))), 1e-9);
}

TEST(MountingFromMotion, TooFewUsableFramesAreNamed) {
  std::vector<MountingFrame> frames = frames_of(Side::kRight, Quat::Identity(), 20, 30 * kDeg, 60 * kDeg);
  for (std::size_t i = 0; i < 10; ++i) frames[i].forearm_K = Vec3(NAN, 0, 0);
  std::string why;
  EXPECT_FALSE(estimate_mounting(frames, Side::kRight, {}, why));
  EXPECT_EQ(why, "the forearm axis was measured at 10 frames; need 15");
}

TEST(MountingFromMotion, PredictedAxisErrorIsOneFramesAgreement) {
  // 2-degree noise on every measured axis: the predicted RMS is the frames' own scatter, not the
  // standard error of their mean (the depth axis's error recurs with the pose rather than
  // averaging out), so the actual error of 150 white-noise frames is far within its 2-D 99 % bound
  // (2.15 x the predicted RMS) in every session.
  int within = 0;
  constexpr int kSessions = 100;
  const Quat F_from_A = rot(0.3, Vec3(0.2, 1, 0.4));
  const std::vector<MountingFrame> exact = frames_of(Side::kRight, F_from_A, 150, 40 * kDeg, 60 * kDeg);
  for (int s = 0; s < kSessions; ++s) {
    std::string why;
    const std::vector<MountingFrame> noisy =
        frames_of(Side::kRight, F_from_A, 150, 40 * kDeg, 60 * kDeg, 2 * kDeg / std::sqrt(3.0), 100 + s);
    const std::optional<MountingEstimate> e = estimate_mounting(noisy, Side::kRight, {}, why);
    ASSERT_TRUE(e) << why;
    const Vec3 true_axis = F_from_A.conjugate() * Vec3::UnitY(), axis = e->F_from_A.conjugate() * Vec3::UnitY();
    const double error = std::acos(std::min(1.0, true_axis.dot(axis)));
    if (error <= 2.15 * e->axis_rms_rad) ++within;
    double scatter_sq = 0;  // each frame's axis error, RMS
    for (std::size_t i = 0; i < noisy.size(); ++i)
      scatter_sq +=
          std::pow(std::acos(std::min(1.0, noisy[i].forearm_K.normalized().dot(exact[i].forearm_K.normalized()))), 2);
    EXPECT_NEAR(e->axis_rms_rad, std::sqrt(scatter_sq / static_cast<double>(noisy.size())), 0.05 * kDeg);
    EXPECT_LT(error, 0.3 * e->axis_rms_rad);  // the mean of 150 independent frames is far better
  }
  EXPECT_EQ(within, kSessions);
}

TEST(OrientationUncertainty, ConfidenceIsHalfWhereThe99PercentBoundIs15Degrees) {
  EXPECT_DOUBLE_EQ(confidence_from_rms_rad(0.0), 1.0);
  EXPECT_NEAR(confidence_from_rms_rad(kConfidentErrorBoundRad / kBound99OverRms), 0.5, 1e-12);
  EXPECT_LT(confidence_from_rms_rad(10 * kDeg), 0.35);
  EXPECT_LT(confidence_from_rms_rad(15 * kDeg), 0.1);
  EXPECT_GT(confidence_from_rms_rad(4 * kDeg), 0.8);
  EXPECT_EQ(confidence_from_rms_rad(NAN), 0.0);
  EXPECT_EQ(confidence_from_rms_rad(-1.0), 0.0);
  double last = 1.0;
  for (double u = 0.5; u < 40; u += 0.5) {
    const double c = confidence_from_rms_rad(u * kDeg);
    EXPECT_LT(c, last);
    last = c;
  }
  EXPECT_NEAR(orientation_rms_rad(3 * kDeg, 4 * kDeg, 0.0), 5 * kDeg, 1e-12);
  EXPECT_NEAR(orientation_rms_rad(0, 0), kFilterRmsRad, 1e-15);
}

}  // namespace
}  // namespace posefuse::forearm
