#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <optional>
#include <random>

#include "body/template_generator.hpp"
#include "fit/arm_roll.hpp"
#include "fit/camera_joints.hpp"
#include "fit/fitted_body_frame.hpp"
#include "fit/pose_smoothing.hpp"
#include "posed_subject.hpp"
#include "synthetic_frames.hpp"

namespace posefuse::fit {
namespace {

using body::PoseLayout;
constexpr double kDeg = std::numbers::pi / 180;

TEST(FitPoseSmoothing, CentredMovingAverageOfThreeFrames) {
  const PoseLayout layout = PoseLayout::upper_body();
  std::vector<Eigen::VectorXd> raw;
  for (int t = 0; t < 6; ++t) raw.push_back(Eigen::VectorXd::Constant(layout.size(), 0.01 * t * t));
  const std::vector<Eigen::VectorXd> smoothed = smooth_poses(layout, raw);
  ASSERT_EQ(smoothed.size(), raw.size());
  // At the ends the window shrinks on both sides and stays centred: the end frames are their own.
  EXPECT_EQ(smoothed[0], raw[0]);
  for (int t = 1; t < 5; ++t) EXPECT_TRUE(smoothed[t].isApprox((raw[t - 1] + raw[t] + raw[t + 1]) / 3)) << t;
  EXPECT_EQ(smoothed[5], raw[5]);
  // Window 1 is the raw sequence; window 5 averages five, three next to an end, one at it.
  EXPECT_EQ(smooth_poses(layout, raw, {1}), raw);
  const std::vector<Eigen::VectorXd> five = smooth_poses(layout, raw, {5});
  EXPECT_TRUE(five[2].isApprox((raw[0] + raw[1] + raw[2] + raw[3] + raw[4]) / 5));
  EXPECT_TRUE(five[1].isApprox((raw[0] + raw[1] + raw[2]) / 3));
  EXPECT_TRUE(five[4].isApprox((raw[3] + raw[4] + raw[5]) / 3));
  EXPECT_EQ(five[5], raw[5]);
}

// A body moving at constant speed: a centred window, however short at the ends, does not lag.
TEST(FitPoseSmoothing, ConstantSpeedIsNotDelayedAtTheEnds) {
  const PoseLayout layout = PoseLayout::upper_body();
  std::vector<Eigen::VectorXd> raw;
  for (int t = 0; t < 7; ++t) raw.push_back(Eigen::VectorXd::Constant(layout.size(), 0.05 * t));
  for (int window : {3, 5}) {
    const std::vector<Eigen::VectorXd> smoothed = smooth_poses(layout, raw, {window});
    for (int t = 0; t < 7; ++t)
      EXPECT_TRUE(smoothed[t].isApprox(raw[t], 1e-12)) << "window " << window << " frame " << t;
  }
}

TEST(FitPoseSmoothing, StreamingEmitsOneFrameLate) {
  const PoseLayout layout = PoseLayout::upper_body();
  PoseSmoother smoother(layout);
  const Eigen::VectorXd a = layout.zero(), b = Eigen::VectorXd::Constant(layout.size(), 0.3);
  EXPECT_FALSE(smoother.push(a).has_value());
  const auto first = smoother.push(b);
  ASSERT_TRUE(first.has_value());
  EXPECT_TRUE(first->isApprox(a));  // the first frame's window is itself
  const auto second = smoother.push(a);
  ASSERT_TRUE(second.has_value());
  EXPECT_TRUE(second->isApprox((a + b + a) / 3));
  const std::vector<Eigen::VectorXd> rest = smoother.flush();
  ASSERT_EQ(rest.size(), 1u);
  EXPECT_TRUE(rest[0].isApprox(a));  // and the last frame's
}

// A subject facing the camera turns slowly through 180 degrees about y, where the pelvis rotation
// vector flips between (0, pi - e, 0) and (0, -(pi - e), 0): the average must stay near the truth.
TEST(FitPoseSmoothing, PelvisRotationIsUnwrappedBeforeAveraging) {
  const PoseLayout layout = PoseLayout::upper_body();
  const int y = layout.index_of("pelvis_y");
  std::vector<Eigen::VectorXd> raw;
  for (int t = 0; t < 5; ++t) {
    Eigen::VectorXd theta = layout.zero();
    const double angle = std::numbers::pi - 0.02 + 0.01 * t;                     // crosses pi
    theta[y] = angle > std::numbers::pi ? angle - 2 * std::numbers::pi : angle;  // as a log map gives it
    raw.push_back(theta);
  }
  const std::vector<Eigen::VectorXd> smoothed = smooth_poses(layout, raw);
  for (int t = 1; t < 4; ++t) {
    const Eigen::AngleAxisd truth(std::numbers::pi - 0.02 + 0.01 * t, Eigen::Vector3d::UnitY());
    const Eigen::AngleAxisd got(std::abs(smoothed[t][y]), Eigen::Vector3d::UnitY() * (smoothed[t][y] < 0 ? -1 : 1));
    EXPECT_LT(Eigen::Quaterniond(truth).angularDistance(Eigen::Quaterniond(got)), 1e-9) << t;
  }
}

TEST(FitPoseSmoothing, BadInputNamesTheField) {
  const PoseLayout layout = PoseLayout::upper_body();
  EXPECT_EQ(testing::error_field([&] { PoseSmoother(layout, {2}); }), "smoothing_options.window_frames");
  EXPECT_EQ(testing::error_field([&] { PoseSmoother(layout, {0}); }), "smoothing_options.window_frames");
  PoseSmoother smoother(layout);
  EXPECT_EQ(testing::error_field([&] { smoother.push(Eigen::VectorXd::Zero(3)); }), "theta");
  Eigen::VectorXd nan = layout.zero();
  nan[4] = std::nan("");
  EXPECT_EQ(testing::error_field([&] { smoother.push(nan); }), "theta");
}

const std::shared_ptr<body::SmplModel>& male() { return testing::template_model(body::Sex::kMale); }

// The IMU's orientation for a forearm whose thumb is turned by `roll` about the forearm from
// `thumb_K`, with the IMU strapped at A_from_F: K_from_A = K_from_F * F_from_A.
Eigen::Quaterniond imu_orientation(const Eigen::Vector3d& along_K, const Eigen::Vector3d& thumb_K, double roll,
                                   const Eigen::Quaterniond& A_from_F) {
  const Eigen::Vector3d thumb = Eigen::AngleAxisd(roll, along_K) * thumb_K;
  Eigen::Matrix3d K_from_F;
  K_from_F.col(0) = thumb;    // thumb_F = x
  K_from_F.col(1) = along_K;  // along_F = y
  K_from_F.col(2) = thumb.cross(along_K);
  return Eigen::Quaterniond(K_from_F) * A_from_F.conjugate();
}

TEST(FitArmRoll, PronationFromNeutralWithTheElbowBent) {
  const PoseLayout layout = PoseLayout::upper_body();
  // Upper arms hanging, elbows bent 90 degrees forward: the roll-free model forearm is in the
  // neutral position (thumb up).
  const Eigen::VectorXd theta = testing::facing_pose(
      layout, 2.0, {{"left_shoulder_z", -90}, {"left_elbow_y", -90}, {"right_shoulder_z", 90}, {"right_elbow_y", 90}});
  const JointPose pose = pose_joints(rest_joints(*male(), Eigen::VectorXd()), layout, theta);
  const Eigen::Quaterniond A_from_F(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -2, 0.5).normalized()));
  for (ArmSide side : {ArmSide::kLeft, ArmSide::kRight}) {
    const bool left = side == ArmSide::kLeft;
    const int elbow = left ? body::kLeftElbow : body::kRightElbow, wrist = left ? body::kLeftWrist : body::kRightWrist;
    const Eigen::Vector3d along = (pose.positions_K.col(wrist) - pose.positions_K.col(elbow)).normalized();
    const Eigen::Vector3d up_K = Eigen::Vector3d::UnitY();                                 // the camera's y is up
    EXPECT_LT((pose.K_from_joint[elbow] * Eigen::Vector3d::UnitZ() - up_K).norm(), 1e-9);  // thumb up
    for (double roll_deg : {-80.0, -20.0, 0.0, 35.0, 90.0}) {
      const ForearmRoll r = forearm_roll(pose, side, imu_orientation(along, up_K, roll_deg * kDeg, A_from_F), A_from_F);
      EXPECT_NEAR(r.roll_rad, roll_deg * kDeg, 1e-9);
      ASSERT_TRUE(r.pronation_rad.has_value());
      // Turning the thumb medially is pronation on both sides.
      const Eigen::Vector3d thumb = Eigen::AngleAxisd(roll_deg * kDeg, along) * up_K;
      // The subject faces the camera: its left arm is on K's -x side, so medial is +x there.
      const Eigen::Vector3d medial = Eigen::Vector3d::UnitX() * (left ? 1.0 : -1.0);
      EXPECT_NEAR(*r.pronation_rad, (left ? 1 : -1) * roll_deg * kDeg, 1e-9);
      if (roll_deg * (left ? 1 : -1) > 0) {
        EXPECT_GT(thumb.dot(medial), 0) << "pronation turns the thumb medially";
      }
      EXPECT_NEAR(r.axis_disagreement_rad, 0, 1e-7);
      EXPECT_LT((r.K_from_forearm * Eigen::Vector3d::UnitZ() - thumb).norm(), 1e-9);
    }
  }
}

TEST(FitArmRoll, RollOfAnyPoseAndNoPronationWithAStraightElbow) {
  const PoseLayout layout = PoseLayout::upper_body();
  const Eigen::Matrix3Xd rest = rest_joints(*male(), Eigen::VectorXd());
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::VectorXd theta = testing::facing_pose(layout, 2.0, {});
    for (int d = 6; d < layout.size(); ++d)
      if (layout.dof(d).limited)
        theta[d] = 0.5 * (layout.dof(d).min_rad + layout.dof(d).max_rad) +
                   0.45 * uniform(rng) * (layout.dof(d).max_rad - layout.dof(d).min_rad);
    const JointPose pose = pose_joints(rest, layout, theta);
    const Eigen::Vector3d along =
        (pose.positions_K.col(body::kLeftWrist) - pose.positions_K.col(body::kLeftElbow)).normalized();
    Eigen::Vector3d thumb = pose.K_from_joint[body::kLeftElbow] * Eigen::Vector3d::UnitZ();
    thumb = (thumb - thumb.dot(along) * along).normalized();
    const double roll = 3.0 * uniform(rng);
    const Eigen::Quaterniond A_from_F(
        Eigen::AngleAxisd(2 * uniform(rng), Eigen::Vector3d(uniform(rng), 1, 0).normalized()));
    const ForearmRoll r = forearm_roll(pose, ArmSide::kLeft, imu_orientation(along, thumb, roll, A_from_F), A_from_F);
    EXPECT_NEAR(r.roll_rad, roll, 1e-9) << trial;
  }
  // Straight arm: roll is defined, pronation is not.
  const JointPose straight = pose_joints(rest, layout, testing::facing_pose(layout, 2.0, {}));
  const Eigen::Vector3d along =
      (straight.positions_K.col(body::kLeftWrist) - straight.positions_K.col(body::kLeftElbow)).normalized();
  const Eigen::Vector3d thumb = straight.K_from_joint[body::kLeftElbow] * Eigen::Vector3d::UnitZ();
  const ForearmRoll r =
      forearm_roll(straight, ArmSide::kLeft, imu_orientation(along, thumb, 0.4, Eigen::Quaterniond::Identity()),
                   Eigen::Quaterniond::Identity());
  EXPECT_NEAR(r.roll_rad, 0.4, 1e-9);
  EXPECT_FALSE(r.pronation_rad.has_value());
}

TEST(FitArmRoll, BadInputNamesTheField) {
  const PoseLayout layout = PoseLayout::upper_body();
  const JointPose pose =
      pose_joints(rest_joints(*male(), Eigen::VectorXd()), layout, testing::facing_pose(layout, 2.0, {}));
  const Eigen::Quaterniond unit = Eigen::Quaterniond::Identity();
  EXPECT_EQ(testing::error_field([&] { forearm_roll(pose, ArmSide::kLeft, Eigen::Quaterniond(2, 0, 0, 0), unit); }),
            "K_from_A");
  EXPECT_EQ(testing::error_field(
                [&] { forearm_roll(pose, ArmSide::kLeft, unit, Eigen::Quaterniond(std::nan(""), 0, 0, 0)); }),
            "A_from_F");
  ArmRollOptions bad;
  bad.thumb_F = Eigen::Vector3d::UnitY();
  EXPECT_EQ(testing::error_field([&] { forearm_roll(pose, ArmSide::kLeft, unit, unit, bad); }),
            "arm_roll_options.thumb_F");
  // An IMU whose thumb axis points along the fitted forearm gives no roll.
  const Eigen::Vector3d along =
      (pose.positions_K.col(body::kLeftWrist) - pose.positions_K.col(body::kLeftElbow)).normalized();
  const Eigen::Quaterniond thumb_along = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitX(), along);
  EXPECT_EQ(testing::error_field([&] { forearm_roll(pose, ArmSide::kLeft, thumb_along, unit); }), "K_from_A");
  JointPose broken = pose;
  broken.positions_K.col(body::kLeftWrist) = broken.positions_K.col(body::kLeftElbow);
  EXPECT_EQ(testing::error_field([&] { forearm_roll(broken, ArmSide::kLeft, unit, unit); }), "pose");
}

// A camera skeleton that sees `pose` exactly, every joint tracked.
TrackedSkeleton tracked_at(const JointPose& pose) {
  const Eigen::Matrix3Xd camera = camera_joints_from_pose(pose);
  TrackedSkeleton skeleton;
  for (int j = 0; j < kKinectJointCount; ++j) skeleton.positions_K[static_cast<size_t>(j)] = camera.col(j);
  skeleton.tracking.fill(JointTracking::kTracked);
  return skeleton;
}

// The male template facing the camera at 2 m and a camera skeleton that sees it exactly (every
// joint tracked), for make_fitted_body_frame.
struct FacingFit {
  PoseLayout layout = PoseLayout::upper_body();
  Eigen::Matrix3Xd rest = rest_joints(*male(), Eigen::VectorXd());
  Eigen::VectorXd theta = testing::facing_pose(layout, 2.0, {});
  JointPose pose = pose_joints(rest, layout, theta);
  TrackedSkeleton skeleton = tracked_at(pose);
  raycast::DepthCamera camera{raycast::DepthIntrinsics{}};

  // An IMU orientation whose y lies along the fitted forearm, so that its roll is defined.
  Eigen::Quaterniond along_forearm(ArmSide side) const {
    const bool left = side == ArmSide::kLeft;
    return Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitY(),
                                              pose.positions_K.col(left ? body::kLeftWrist : body::kRightWrist) -
                                                  pose.positions_K.col(left ? body::kLeftElbow : body::kRightElbow));
  }
  FittedBodyFrame fitted(const ForearmOrientationPair& K_from_F = {}) const {
    return make_fitted_body_frame(rest, layout, theta, skeleton, camera, K_from_F);
  }
};

// A fitted joint's confidence follows the camera's tracking of the joint it corresponds to: 1
// tracked; untracked, 0 for the wrist and hand (angles read from them cannot be acted on,
// docs/fitting.md "Joint confidence") and 0.5 for the others. The fitted forearm takes its
// wrist's.
TEST(FittedBodyFrame, JointConfidenceFollowsTheCameraTrackingState) {
  FacingFit fit;
  fit.skeleton.tracking[kWristLeft] = JointTracking::kInferred;
  fit.skeleton.tracking[kElbowRight] = JointTracking::kInferred;
  fit.skeleton.tracking[kSpineMid] = JointTracking::kNotTracked;
  const FittedBodyFrame frame = fit.fitted({fit.along_forearm(ArmSide::kLeft), fit.along_forearm(ArmSide::kRight)});
  ASSERT_EQ(frame.smpl_joints.size(), static_cast<size_t>(body::kNumJoints));
  EXPECT_DOUBLE_EQ(frame.smpl_joints[body::kLeftWrist].confidence, 0.0);
  EXPECT_DOUBLE_EQ(frame.smpl_joints[body::kRightElbow].confidence, 0.5);
  EXPECT_DOUBLE_EQ(frame.smpl_joints[body::kRightWrist].confidence, 1.0);
  EXPECT_DOUBLE_EQ(frame.smpl_joints[body::kLeftElbow].confidence, 1.0);
  EXPECT_DOUBLE_EQ(frame.camera_joints[kWristLeft].confidence, 0.0);
  EXPECT_DOUBLE_EQ(frame.camera_joints[kSpineMid].confidence, 0.5);
  ASSERT_EQ(frame.forearms.size(), 2u);
  for (const FittedForearm& forearm : frame.forearms)
    EXPECT_DOUBLE_EQ(forearm.confidence, forearm.side == ArmSide::kLeft ? 0.0 : 1.0);
}

// The SMPL joints with no camera joint are trusted no more than the camera-backed joints around
// them: with the left shoulder inferred the left collar and spine3 take its 0.5, the right collar
// keeps 1; with the neck untracked the head follows it; with every joint tracked all are 1.
TEST(FittedBodyFrame, JointsWithoutACameraJointTakeTheirNeighboursConfidence) {
  FacingFit fit;
  for (const FittedJoint& joint : fit.fitted().smpl_joints) EXPECT_DOUBLE_EQ(joint.confidence, 1.0);
  fit.skeleton.tracking[kShoulderLeft] = JointTracking::kInferred;
  fit.skeleton.tracking[kNeck] = JointTracking::kNotTracked;
  const FittedBodyFrame frame = fit.fitted();
  EXPECT_DOUBLE_EQ(frame.smpl_joints[body::kLeftCollar].confidence, 0.5);
  EXPECT_DOUBLE_EQ(frame.smpl_joints[body::kSpine3].confidence, 0.5);
  EXPECT_DOUBLE_EQ(frame.smpl_joints[body::kHead].confidence, 0.5);
  EXPECT_DOUBLE_EQ(frame.smpl_joints[body::kRightCollar].confidence, 1.0);
  EXPECT_DOUBLE_EQ(frame.smpl_joints[body::kSpine1].confidence, 1.0);
}

// A camera joint reported TRACKED far from the fitted joint (a fit folded into a wrong pose, or
// the camera off track): the camera's own view contradicts the fitted joint, which has no
// confidence then, not even an untracked elbow's 0.5, and the frame counts it. Within
// kCameraDisagreementM it stays 1.
TEST(FittedBodyFrame, ATrackedJointFarFromTheFitDoesNotVouchForIt) {
  FacingFit fit;
  const Eigen::Vector3d just_within(0, kCameraDisagreementM - 0.01, 0), beyond(0, 0, kCameraDisagreementM + 0.01);
  fit.skeleton.positions_K[kWristLeft] += beyond;  // the camera's wrist where the fit's is not
  fit.skeleton.positions_K[kElbowLeft] += beyond;
  fit.skeleton.positions_K[kShoulderLeft] += beyond;
  fit.skeleton.positions_K[kWristRight] += just_within;  // the camera's usual error
  fit.skeleton.positions_K[kElbowRight] += beyond;
  fit.skeleton.tracking[kElbowRight] = JointTracking::kInferred;  // untracked anyway: not counted
  const FittedBodyFrame frame = fit.fitted();
  EXPECT_DOUBLE_EQ(frame.smpl_joints[body::kLeftWrist].confidence, 0.0);
  EXPECT_DOUBLE_EQ(frame.smpl_joints[body::kLeftElbow].confidence, 0.0);
  EXPECT_DOUBLE_EQ(frame.smpl_joints[body::kLeftShoulder].confidence, 0.0);
  EXPECT_DOUBLE_EQ(frame.camera_joints[kWristLeft].confidence, 0.0);
  EXPECT_DOUBLE_EQ(frame.camera_joints[kElbowLeft].confidence, 0.0);
  EXPECT_DOUBLE_EQ(frame.smpl_joints[body::kRightWrist].confidence, 1.0);
  EXPECT_DOUBLE_EQ(frame.smpl_joints[body::kRightElbow].confidence, 0.5);
  EXPECT_DOUBLE_EQ(frame.smpl_joints[body::kRightShoulder].confidence, 1.0);
  EXPECT_EQ(frame.joints_off_camera, 3);
}

// A fitted joint outside the depth image has no confidence, whatever the camera reports: nothing
// the camera gives sees it. With the image ending 20 px right of the optical axis, the subject's
// right arm (x > 0 at 2 m) lies outside it; the left arm stays in view and keeps 1.
TEST(FittedBodyFrame, AJointOutsideTheImageHasNoConfidence) {
  FacingFit fit;
  EXPECT_EQ(fit.fitted().joints_out_of_view, 0);
  raycast::DepthIntrinsics cut;
  cut.cx = 20;
  const raycast::DepthCamera camera{cut};
  const FittedBodyFrame frame =
      make_fitted_body_frame(fit.rest, fit.layout, fit.theta, fit.skeleton, camera,
                             {fit.along_forearm(ArmSide::kLeft), fit.along_forearm(ArmSide::kRight)});
  for (const int j : {body::kRightShoulder, body::kRightElbow, body::kRightWrist})
    EXPECT_DOUBLE_EQ(frame.smpl_joints[static_cast<size_t>(j)].confidence, 0.0) << j;
  for (const int j : {body::kLeftShoulder, body::kLeftElbow, body::kLeftWrist})
    EXPECT_DOUBLE_EQ(frame.smpl_joints[static_cast<size_t>(j)].confidence, 1.0) << j;
  EXPECT_DOUBLE_EQ(frame.camera_joints[kHandRight].confidence, 0.0);
  int outside = 0;
  for (const FittedJoint& joint : frame.camera_joints) {
    const auto px = camera.project(joint.p_K);
    outside += !px || px->x() < 0;
  }
  EXPECT_GE(outside, 6);
  EXPECT_EQ(frame.joints_out_of_view, outside);
  ASSERT_EQ(frame.forearms.size(), 2u);
  for (const FittedForearm& forearm : frame.forearms)
    EXPECT_DOUBLE_EQ(forearm.confidence, forearm.side == ArmSide::kLeft ? 1.0 : 0.0);
}

// An untrusted fit's frame (energy above the tracker's trusted_energy): every joint and forearm
// confidence is capped at the confidence of the 99 % bound measured for such frames, 47.0 degrees,
// 2^-(47.0/15)^2; lower confidences stay as they were.
TEST(FittedBodyFrame, AnUntrustedFitCapsEveryConfidence) {
  EXPECT_NEAR(untrusted_fit_confidence(), std::pow(2.0, -std::pow(47.0 / 15.0, 2)), 1e-12);
  FacingFit fit;
  fit.skeleton.tracking[kWristLeft] = JointTracking::kInferred;
  FittedBodyFrame frame = fit.fitted({std::nullopt, fit.along_forearm(ArmSide::kRight)});
  ASSERT_EQ(frame.forearms.size(), 1u);
  ASSERT_EQ(frame.forearms[0].confidence, 1.0);
  cap_confidence(frame, 0.25);
  for (const FittedJoint& joint : frame.smpl_joints) EXPECT_LE(joint.confidence, 0.25);
  EXPECT_EQ(frame.smpl_joints[body::kRightWrist].confidence, 0.25);
  EXPECT_EQ(frame.smpl_joints[body::kLeftWrist].confidence, 0.0);
  EXPECT_EQ(frame.camera_joints[kSpineMid].confidence, 0.25);
  EXPECT_EQ(frame.camera_joints[kWristLeft].confidence, 0.0);
  EXPECT_EQ(frame.forearms[0].confidence, 0.25);
}

}  // namespace
}  // namespace posefuse::fit
