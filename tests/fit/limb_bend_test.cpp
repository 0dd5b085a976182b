// The legs a frame's fit holds straight: those the camera does not show bent beyond what its
// joint error bends a straight leg.
#include "fit/limb_bend.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace posefuse::fit {
namespace {

constexpr double kDeg = std::numbers::pi / 180;

TEST(FitLimbBend, BendIsTheAngleBetweenTheSegments) {
  const Eigen::Vector3d hip(0, 1, 3), knee(0, 0.58, 3);
  EXPECT_NEAR(limb_bend_deg(hip, knee, Eigen::Vector3d(0, 0.16, 3)), 0, 1e-9);
  EXPECT_NEAR(limb_bend_deg(hip, knee, knee + 0.42 * Eigen::Vector3d(0, -std::cos(30 * kDeg), std::sin(30 * kDeg))), 30,
              1e-9);
  EXPECT_NEAR(limb_bend_deg(hip, knee, knee + Eigen::Vector3d(0, 0, -0.4)), 90, 1e-9);
}

TEST(FitLimbBend, AMiddleJointOffTheLineBendsAStraightLimb) {
  const Eigen::Vector3d hip(0, 1, 3), knee(0, 0.58, 3), ankle(0, 0.16, 3);
  const double expected = 2 * std::atan2(0.05, 0.42) / kDeg;
  EXPECT_NEAR(bend_from_offset_deg(hip, knee, ankle, 0.05), expected, 1e-9);
  EXPECT_NEAR(expected, 13.6, 0.05);
  EXPECT_EQ(bend_from_offset_deg(hip, knee, ankle, 0.0), 0.0);
  // The knee really moved 5 cm across: the bend it shows is the one allowed.
  EXPECT_NEAR(limb_bend_deg(hip, knee + Eigen::Vector3d(0, 0, 0.05), ankle), expected, 1e-9);
}

// A standing skeleton (K: x right, y up, z away from the camera) with the left knee bent by
// `left_knee_deg` forward and the right leg straight.
TrackedSkeleton standing(double left_knee_deg) {
  KinectSkeleton p{};
  for (auto& joint : p) joint = Eigen::Vector3d(0, 1.2, 3);
  p[kHipLeft] = Eigen::Vector3d(-0.1, 1.0, 3);
  p[kKneeLeft] = Eigen::Vector3d(-0.1, 0.58, 3);
  p[kAnkleLeft] =
      p[kKneeLeft] + 0.42 * Eigen::Vector3d(0, -std::cos(left_knee_deg * kDeg), -std::sin(left_knee_deg * kDeg));
  p[kHipRight] = Eigen::Vector3d(0.1, 1.0, 3);
  p[kKneeRight] = Eigen::Vector3d(0.1, 0.58, 3);
  p[kAnkleRight] = Eigen::Vector3d(0.1, 0.16, 3);
  return TrackedSkeleton::all_tracked(p);
}

// Hip, knee and ankle each 5 cm off, the knee one way and the ends the other, put the knee 10 cm
// off the hip - ankle line: 2 atan(0.1 / 0.42) = 26.8 deg.
TEST(FitLimbBend, ALegIsBentWhenItsTrackedKneeBendsBeyondWhatTheJointErrorsAllow) {
  const TrackedSkeleton at_25 = standing(25), at_29 = standing(29), at_1 = standing(1);
  const BentLegs straight = camera_bent_legs(&at_25);
  EXPECT_FALSE(straight.left);
  EXPECT_FALSE(straight.right);
  const BentLegs bent = camera_bent_legs(&at_29);
  EXPECT_TRUE(bent.left);
  EXPECT_FALSE(bent.right);
  // An exact camera: any bend counts.
  EXPECT_TRUE(camera_bent_legs(&at_1, 0.0).left);
}

TEST(FitLimbBend, AGuessedOrMissingLegIsNotBent) {
  TrackedSkeleton inferred = standing(60);
  inferred.tracking[kAnkleLeft] = JointTracking::kInferred;
  EXPECT_FALSE(camera_bent_legs(&inferred).left);
  TrackedSkeleton not_finite = standing(60);
  not_finite.positions_K[kKneeLeft].x() = std::nan("");
  EXPECT_FALSE(camera_bent_legs(&not_finite).left);
  EXPECT_FALSE(camera_bent_legs(nullptr).left);
  EXPECT_FALSE(camera_bent_legs(nullptr).right);
}

TEST(FitLimbBend, HeldDofsAreTheKneesAndAnklesOfTheStraightLegs) {
  const body::PoseLayout full = body::PoseLayout::full_body();
  const std::vector<int> both = held_leg_dofs(full, {});
  ASSERT_EQ(both.size(), 8u);
  for (int d : both) {
    const int joint = full.dof(d).joint;
    EXPECT_TRUE(joint == body::kLeftKnee || joint == body::kRightKnee || joint == body::kLeftAnkle ||
                joint == body::kRightAnkle)
        << full.dof(d).name;
  }
  EXPECT_TRUE(std::is_sorted(both.begin(), both.end()));
  const std::vector<int> right_only = held_leg_dofs(full, {.left = true, .right = false});
  ASSERT_EQ(right_only.size(), 4u);
  for (int d : right_only) EXPECT_NE(full.dof(d).name.find("right_"), std::string::npos) << full.dof(d).name;
  EXPECT_TRUE(held_leg_dofs(full, {.left = true, .right = true}).empty());
  EXPECT_TRUE(held_leg_dofs(body::PoseLayout::upper_body(), {}).empty());
}

}  // namespace
}  // namespace posefuse::fit
