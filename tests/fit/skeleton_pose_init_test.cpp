#include "fit/skeleton_pose_init.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <numbers>

#include "body/template_generator.hpp"
#include "common/error.hpp"
#include "posed_subject.hpp"
#include "synthetic_frames.hpp"

namespace posefuse::fit {
namespace {

using body::PoseLayout;

const std::shared_ptr<body::SmplModel>& male() { return testing::template_model(body::Sex::kMale); }

Eigen::VectorXd shape() {
  Eigen::VectorXd beta = Eigen::VectorXd::Zero(10);
  beta << 0.8, -0.5, 0.3, 1.0, -0.7, 0.6, 0, 0, 0, 0;
  return beta;
}

// A pose inside the limits with the trunk turned, bent and tilted, one shoulder lifted and
// every arm joint bent.
Eigen::VectorXd known_pose(const PoseLayout& layout) {
  return testing::facing_pose(
      layout, 2.3,
      {{"pelvis_x", 8},          {"pelvis_y", -15},        {"pelvis_z", 5},          {"spine2_x", 10},
       {"spine2_z", -6},         {"spine3_x", 6},          {"spine3_y", 8},          {"neck_x", 15},
       {"neck_z", -10},          {"left_collar_z", 15},    {"right_collar_y", 8},    {"left_shoulder_y", -30},
       {"left_shoulder_z", -50}, {"right_shoulder_y", 20}, {"right_shoulder_z", 70}, {"left_elbow_y", -80},
       {"left_elbow_z", 10},     {"right_elbow_y", 45},    {"left_wrist_y", 20},     {"right_wrist_z", -25},
       {"left_hip_x", -20},      {"right_hip_z", -10}});
}

double max_joint_error(const JointPose& a, const JointPose& b, std::initializer_list<int> joints) {
  double worst = 0;
  for (int j : joints) worst = std::max(worst, (a.positions_K.col(j) - b.positions_K.col(j)).norm());
  return worst;
}

constexpr std::initializer_list<int> kArmJoints = {body::kLeftShoulder, body::kRightShoulder, body::kLeftElbow,
                                                   body::kRightElbow,   body::kLeftWrist,     body::kRightWrist,
                                                   body::kLeftHand,     body::kRightHand};
constexpr std::initializer_list<int> kTrunkJoints = {
    body::kPelvis, body::kLeftHip,    body::kRightHip,    body::kSpine2,   body::kSpine3,   body::kNeck,
    body::kHead,   body::kLeftCollar, body::kRightCollar, body::kLeftKnee, body::kRightKnee};

TEST(FitSkeletonInit, ErrorFreeSkeletonGivesTheKnownJoints) {
  const PoseLayout layout = PoseLayout::upper_body();
  const Eigen::VectorXd beta = shape();
  const testing::PosedSubject truth = testing::pose_subject(*male(), layout, beta, known_pose(layout));
  const SkeletonPoseInitializer init(male(), layout, beta);
  const SkeletonInitResult result = init.initialise(truth.skeleton, Eigen::VectorXd());
  EXPECT_TRUE(result.fallbacks.empty()) << result.fallbacks.front().reason;
  const JointPose built = pose_joints(init.rest_joints(), layout, result.theta);
  // The arms aim at the observed joints; the trunk is a rigid fit of the straight rest trunk plus
  // an upper-trunk rotation split equally between spine2 and spine3 (spine1 stays 0), so a bent
  // trunk is matched only approximately.
  EXPECT_LT(max_joint_error(built, truth.joints, kArmJoints), 0.02);
  EXPECT_LT(max_joint_error(built, truth.joints, kTrunkJoints), 0.04);  // measured 32 mm (the neck)
  EXPECT_LT((built.positions_K.col(body::kPelvis) - truth.joints.positions_K.col(body::kPelvis)).norm(), 0.01);
}

TEST(FitSkeletonInit, FullBodyLayoutBuildsTheKnees) {
  const PoseLayout layout = PoseLayout::full_body();
  const Eigen::VectorXd theta = testing::facing_pose(layout, 2.8,
                                                     {{"left_hip_x", -30},
                                                      {"left_knee_x", 60},
                                                      {"right_hip_z", -15},
                                                      {"right_knee_x", 20},
                                                      {"left_shoulder_z", -70},
                                                      {"right_shoulder_z", 70}});
  const testing::PosedSubject truth = testing::pose_subject(*male(), layout, Eigen::VectorXd(), theta);
  const SkeletonPoseInitializer init(male(), layout, Eigen::VectorXd());
  const SkeletonInitResult result = init.initialise(truth.skeleton, Eigen::VectorXd());
  const JointPose built = pose_joints(init.rest_joints(), layout, result.theta);
  EXPECT_LT(
      max_joint_error(built, truth.joints, {body::kLeftKnee, body::kRightKnee, body::kLeftAnkle, body::kRightAnkle}),
      0.01);
}

TEST(FitSkeletonInit, PoseIsClampedIntoTheLimits) {
  const PoseLayout layout = PoseLayout::upper_body();
  testing::PosedSubject truth = testing::pose_subject(*male(), layout, Eigen::VectorXd(), known_pose(layout));
  // An elbow bent backwards by 60 degrees: outside left_elbow_y's [-155, 10] degrees.
  const Eigen::Vector3d elbow = truth.skeleton.positions_K[kElbowLeft];
  const Eigen::Vector3d upper = elbow - truth.skeleton.positions_K[kShoulderLeft];
  const Eigen::Vector3d forearm = truth.skeleton.positions_K[kWristLeft] - elbow;
  const Eigen::Vector3d hinge = upper.cross(forearm).normalized();
  truth.skeleton.positions_K[kWristLeft] = elbow + Eigen::AngleAxisd(-2.4, hinge) * forearm;
  const SkeletonPoseInitializer init(male(), layout, Eigen::VectorXd());
  const SkeletonInitResult result = init.initialise(truth.skeleton, Eigen::VectorXd());
  ASSERT_FALSE(result.clamped_dofs.empty());
  for (int d = 0; d < layout.size(); ++d) {
    const body::Dof& dof = layout.dof(d);
    if (!dof.limited) continue;
    EXPECT_GE(result.theta[d], dof.min_rad) << dof.name;
    EXPECT_LE(result.theta[d], dof.max_rad) << dof.name;
  }
}

TEST(FitSkeletonInit, MissingJointsKeepThePreviousSegmentsAndSaySo) {
  const PoseLayout layout = PoseLayout::upper_body();
  const Eigen::VectorXd beta = shape();
  const testing::PosedSubject truth = testing::pose_subject(*male(), layout, beta, known_pose(layout));
  const SkeletonPoseInitializer init(male(), layout, beta);
  const SkeletonInitResult full = init.initialise(truth.skeleton, Eigen::VectorXd());

  TrackedSkeleton damaged = truth.skeleton;
  damaged.tracking[kElbowLeft] = JointTracking::kInferred;
  damaged.positions_K[kWristRight] = Eigen::Vector3d(std::nan(""), 0, 2);
  damaged.tracking[kHead] = JointTracking::kNotTracked;
  Eigen::VectorXd previous = layout.zero();
  for (int d = 0; d < layout.size(); ++d) previous[d] = 0.01 * (d % 7) - 0.03;  // within every limit
  const SkeletonInitResult result = init.initialise(damaged, previous);

  // A segment needs the observed joint it aims at (the model's own joint is the other end).
  const std::pair<InitSegment, const char*> expected[] = {{InitSegment::kNeck, "Head is not tracked"},
                                                          {InitSegment::kLeftShoulder, "ElbowLeft is inferred"},
                                                          {InitSegment::kRightElbow, "WristRight is not finite"}};
  ASSERT_EQ(result.fallbacks.size(), std::size(expected));
  for (size_t i = 0; i < std::size(expected); ++i) {
    EXPECT_EQ(result.fallbacks[i].segment, expected[i].first);
    EXPECT_NE(result.fallbacks[i].reason.find(expected[i].second), std::string::npos) << result.fallbacks[i].reason;
    EXPECT_NE(result.fallbacks[i].reason.find("previous pose"), std::string::npos);
  }
  auto dofs_of = [&](int joint) { return layout.dofs_of_joint(joint); };
  for (int joint : {body::kNeck, body::kLeftShoulder, body::kRightElbow})
    for (int d : dofs_of(joint)) EXPECT_EQ(result.theta[d], previous[d]) << layout.dof(d).name;
  // Segments with their joints are built from this skeleton as before (a child of a segment that
  // fell back, like the left elbow, is aimed from its parent's kept pose instead).
  for (int joint : {body::kPelvis, body::kSpine2, body::kLeftCollar, body::kRightShoulder, body::kLeftHip})
    for (int d : dofs_of(joint)) EXPECT_NEAR(result.theta[d], full.theta[d], 1e-12) << layout.dof(d).name;

  // Accepting inferred joints builds the left arm again.
  SkeletonInitOptions accept;
  accept.accept_inferred_joints = true;
  const SkeletonInitResult accepted =
      SkeletonPoseInitializer(male(), layout, beta, accept).initialise(damaged, previous);
  EXPECT_FALSE(accepted.fell_back(InitSegment::kLeftShoulder));
  for (int d : dofs_of(body::kLeftShoulder)) EXPECT_NEAR(accepted.theta[d], full.theta[d], 1e-12);
}

TEST(FitSkeletonInit, FirstFrameWithoutAPreviousPose) {
  const PoseLayout layout = PoseLayout::upper_body();
  const testing::PosedSubject truth = testing::pose_subject(*male(), layout, Eigen::VectorXd(), known_pose(layout));
  const SkeletonPoseInitializer init(male(), layout, Eigen::VectorXd());
  // A missing arm joint leaves the arm at the rest pose and says so.
  TrackedSkeleton no_wrist = truth.skeleton;
  no_wrist.tracking[kWristLeft] = JointTracking::kNotTracked;
  const SkeletonInitResult result = init.initialise(no_wrist, Eigen::VectorXd());
  ASSERT_TRUE(result.fell_back(InitSegment::kLeftElbow));
  EXPECT_NE(result.fallbacks.front().reason.find("rest pose"), std::string::npos);
  for (int d : layout.dofs_of_joint(body::kLeftElbow)) EXPECT_EQ(result.theta[d], 0.0);
  // With only the two shoulders of the trunk there is no global pose to start from ...
  TrackedSkeleton no_trunk = truth.skeleton;
  for (int j : {kSpineBase, kSpineMid, kHipLeft, kHipRight, kSpineShoulder})
    no_trunk.tracking[j] = JointTracking::kInferred;
  EXPECT_EQ(testing::error_field([&] { init.initialise(no_trunk, Eigen::VectorXd()); }), "skeleton.SpineBase");
  // ... but with a previous pose the global segment falls back, and one hip is enough with the rest.
  EXPECT_TRUE(init.initialise(no_trunk, known_pose(layout)).fell_back(InitSegment::kGlobal));
  TrackedSkeleton no_hip = truth.skeleton;
  no_hip.tracking[kHipLeft] = JointTracking::kNotTracked;
  EXPECT_FALSE(init.initialise(no_hip, Eigen::VectorXd()).fell_back(InitSegment::kGlobal));
}

TEST(FitSkeletonInit, NothingUsableIsAClearError) {
  const PoseLayout layout = PoseLayout::upper_body();
  const SkeletonPoseInitializer init(male(), layout, Eigen::VectorXd());
  TrackedSkeleton none;  // every joint not tracked
  EXPECT_EQ(testing::error_field([&] { init.initialise(none, layout.zero()); }), "skeleton");
  TrackedSkeleton nan_joints = TrackedSkeleton::all_tracked({});
  for (auto& p : nan_joints.positions_K) p = Eigen::Vector3d::Constant(std::nan(""));
  EXPECT_EQ(testing::error_field([&] { init.initialise(nan_joints, layout.zero()); }), "skeleton");
  const testing::PosedSubject truth = testing::pose_subject(*male(), layout, Eigen::VectorXd(), known_pose(layout));
  EXPECT_EQ(testing::error_field([&] { init.initialise(truth.skeleton, Eigen::VectorXd::Zero(3)); }), "previous_theta");
  Eigen::VectorXd nan_previous = layout.zero();
  nan_previous[7] = std::nan("");
  EXPECT_EQ(testing::error_field([&] { init.initialise(truth.skeleton, nan_previous); }), "previous_theta");
  SkeletonInitOptions bad;
  bad.min_bone_length_m = 0;
  EXPECT_EQ(testing::error_field([&] { SkeletonPoseInitializer(male(), layout, Eigen::VectorXd(), bad); }),
            "init_options.min_bone_length_m");
  EXPECT_EQ(testing::error_field([&] { SkeletonPoseInitializer(male(), layout, Eigen::VectorXd::Ones(11)); }), "beta");
}

// Facing the camera puts the pelvis rotation vector near |pi|, where its two representations
// differ by 2 pi; the built one stays next to the previous frame's so theta can be averaged.
TEST(FitSkeletonInit, PelvisRotationStaysContinuousNearHalfATurn) {
  const PoseLayout layout = PoseLayout::upper_body();
  const SkeletonPoseInitializer init(male(), layout, Eigen::VectorXd());
  const int pelvis_y = layout.index_of("pelvis_y");
  for (double turn_deg : {-3.0, 3.0}) {
    const Eigen::VectorXd theta = testing::facing_pose(layout, 2.0, {{"pelvis_y", turn_deg}});
    const testing::PosedSubject truth = testing::pose_subject(*male(), layout, Eigen::VectorXd(), theta);
    const Eigen::VectorXd previous = testing::facing_pose(layout, 2.0, {});
    const SkeletonInitResult result = init.initialise(truth.skeleton, previous);
    EXPECT_NEAR(result.theta[pelvis_y], theta[pelvis_y], 1e-6) << turn_deg;
  }
}

}  // namespace
}  // namespace posefuse::fit
