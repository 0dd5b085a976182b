#include "fit/body_tracker.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "body/standing_height.hpp"
#include "model_frames.hpp"
#include "posed_subject.hpp"
#include "synthetic_frames.hpp"

namespace posefuse::fit {
namespace {

using body::PoseLayout;

const std::shared_ptr<body::SmplModel>& female() { return testing::template_model(body::Sex::kFemale); }

// The controlled pose of personalisation (III): facing the camera, arms straight, 60 degrees out.
TrackedSkeleton controlled_pose_skeleton() {
  const PoseLayout layout = PoseLayout::full_body();
  Eigen::VectorXd beta = Eigen::VectorXd::Zero(10);
  beta << 0.8, -0.5, 0.6, 1.0, -0.7, 0.6, 0.4, 0.5, -0.3, 0.5;
  const Eigen::VectorXd theta = testing::facing_pose(layout, 3.2, {{"left_shoulder_z", -30}, {"right_shoulder_z", 30}});
  return testing::pose_subject(*female(), layout, beta, theta).skeleton;
}

BodyTrackerOptions rough_shape_only() {
  BodyTrackerOptions options;
  options.calibration_s = 0.5;
  options.fine_shape = false;  // III-A alone: no depth needed
  options.lost_energy = 100;
  return options;
}

BodyFitFrame frame_at(std::int64_t t_us, std::optional<TrackedSkeleton> skeleton) {
  BodyFitFrame frame;
  frame.t_us = t_us;
  frame.skeleton = std::move(skeleton);
  return frame;
}

std::optional<ForearmOrientationSample> no_orientation(ArmSide, std::int64_t) { return std::nullopt; }

TEST(FitBodyTracker, SkeletonStartPolicy) {
  EXPECT_TRUE(needs_skeleton_start(std::nullopt, 45));  // no previous frame: the skeleton start alone
  EXPECT_TRUE(needs_skeleton_start(45, 45));
  EXPECT_TRUE(needs_skeleton_start(std::nan(""), 45));
  EXPECT_FALSE(needs_skeleton_start(44.9, 45));
  EXPECT_TRUE(needs_skeleton_start(1.0, 0));  // policy off: always both
}

// The calibration frames are held until the first frame after calibration_s, which personalises;
// then they come back, in time order, with that frame.
TEST(FitBodyTracker, CalibrationFramesComeBackWithTheFirstFrameAfterThem) {
  BodyTracker tracker(female(), raycast::DepthIntrinsics{}, rough_shape_only());
  const TrackedSkeleton skeleton = controlled_pose_skeleton();
  for (std::int64_t t = 0; t < 500'000; t += 100'000) {
    const BodyTracker::Admitted admitted = tracker.admit(frame_at(t, skeleton));
    EXPECT_TRUE(admitted.frames.empty()) << t;
    EXPECT_TRUE(admitted.warnings.empty()) << t;
  }
  EXPECT_FALSE(tracker.personalised());
  EXPECT_EQ(tracker.oldest_held_t_us(), std::optional<std::int64_t>(0));
  EXPECT_FALSE(tracker.shape());

  const BodyTracker::Admitted admitted = tracker.admit(frame_at(500'000, skeleton));
  EXPECT_TRUE(admitted.warnings.empty());
  ASSERT_EQ(admitted.frames.size(), 6u);
  for (std::size_t i = 0; i < admitted.frames.size(); ++i)
    EXPECT_EQ(admitted.frames[i].t_us, 100'000 * static_cast<std::int64_t>(i));
  EXPECT_TRUE(tracker.personalised());
  EXPECT_FALSE(tracker.oldest_held_t_us());
  const std::optional<FittedShape> shape = tracker.shape();
  ASSERT_TRUE(shape);
  EXPECT_TRUE(shape->estimated);
  EXPECT_GT(shape->beta.norm(), 0.1);
  EXPECT_EQ(shape->rest_joints_K.cols(), body::kNumJoints);

  // After personalisation every frame comes back at once.
  EXPECT_EQ(tracker.admit(frame_at(600'000, skeleton)).frames.size(), 1u);
}

// Without usable calibration skeletons the template shape is fitted, and the tracker says why.
TEST(FitBodyTracker, RefusedPersonalisationFitsTheTemplateShape) {
  BodyTracker tracker(female(), raycast::DepthIntrinsics{}, rough_shape_only());
  tracker.admit(frame_at(0, std::nullopt));
  const BodyTracker::Admitted admitted = tracker.personalise_now();
  ASSERT_EQ(admitted.warnings.size(), 1u);
  EXPECT_EQ(admitted.warnings[0].code, "FIT_PERSONALISATION");
  EXPECT_EQ(admitted.frames.size(), 1u);
  const std::optional<FittedShape> shape = tracker.shape();
  ASSERT_TRUE(shape);
  EXPECT_FALSE(shape->estimated);
  EXPECT_TRUE(shape->beta.isZero());
}

// With the subject's measured height, a refused personalisation fits the shape of that height.
TEST(FitBodyTracker, RefusedPersonalisationFitsTheShapeOfTheSubjectsHeight) {
  BodyTrackerOptions options = rough_shape_only();
  options.subject_height_m = 1.75;
  BodyTracker tracker(female(), raycast::DepthIntrinsics{}, options);
  tracker.admit(frame_at(0, std::nullopt));
  const BodyTracker::Admitted admitted = tracker.personalise_now();
  ASSERT_EQ(admitted.warnings.size(), 1u);
  EXPECT_EQ(admitted.warnings[0].code, "FIT_PERSONALISATION");
  EXPECT_NE(admitted.warnings[0].message.find("height"), std::string::npos) << admitted.warnings[0].message;
  const std::optional<FittedShape> shape = tracker.shape();
  ASSERT_TRUE(shape);
  EXPECT_FALSE(shape->estimated);
  EXPECT_NEAR(body::standing_height(*female(), shape->beta).height_m, 1.75, 0.01);  // the height's sigma
  options.subject_height_m = 3.1;
  EXPECT_EQ(testing::error_field([&] { BodyTracker(female(), raycast::DepthIntrinsics{}, options); }), "height_m");
}

// A fine tuning that refuses (here: no depth to fit) leaves the template shape, not the rough
// shape, whose arms follow the camera skeleton's joint errors.
TEST(FitBodyTracker, RefusedFineTuningFitsTheTemplateShape) {
  BodyTrackerOptions options = rough_shape_only();
  options.fine_shape = true;
  BodyTracker tracker(female(), raycast::DepthIntrinsics{}, options);
  tracker.admit(frame_at(0, controlled_pose_skeleton()));
  const BodyTracker::Admitted admitted = tracker.personalise_now();
  ASSERT_EQ(admitted.warnings.size(), 1u);
  EXPECT_EQ(admitted.warnings[0].code, "FIT_FINE_SHAPE");
  EXPECT_NE(admitted.warnings[0].message.find("template shape"), std::string::npos) << admitted.warnings[0].message;
  const std::optional<FittedShape> shape = tracker.shape();
  ASSERT_TRUE(shape);
  EXPECT_FALSE(shape->estimated);
  EXPECT_TRUE(shape->beta.isZero());
}

// The camera's elbow 12 cm off across a straight arm: it looks bent about 49 degrees, past the
// controlled pose's 40 but within what the camera's arm joint error allows.
TrackedSkeleton camera_bent_elbow_skeleton() {
  TrackedSkeleton skeleton = controlled_pose_skeleton();
  skeleton.positions_K[kElbowLeft] += Eigen::Vector3d(0, 0, -0.12);
  return skeleton;
}

std::optional<FittedShape> rough_shape_from(const std::vector<TrackedSkeleton>& skeletons,
                                            std::vector<FitWarning>* warnings = nullptr) {
  BodyTracker tracker(female(), raycast::DepthIntrinsics{}, rough_shape_only());
  std::int64_t t = 0;
  for (const TrackedSkeleton& s : skeletons) tracker.admit(frame_at(t += 100'000, s));
  const BodyTracker::Admitted admitted = tracker.personalise_now();
  if (warnings) *warnings = admitted.warnings;
  return tracker.shape();
}

TEST(FitBodyTracker, PersonalisesFromTheFramesWhoseElbowsLookStraightestItCan) {
  // Every frame's elbow looks bent within the camera's error: personalised from them.
  std::vector<FitWarning> warnings;
  const std::optional<FittedShape> bent_only =
      rough_shape_from(std::vector<TrackedSkeleton>(3, camera_bent_elbow_skeleton()), &warnings);
  ASSERT_TRUE(bent_only);
  EXPECT_TRUE(bent_only->estimated);
  EXPECT_TRUE(warnings.empty());
  // With frames that show the pose even with the camera taken as exact, only those count: the
  // shape is the straight frames' alone.
  const std::optional<FittedShape> straight_only =
      rough_shape_from(std::vector<TrackedSkeleton>(2, controlled_pose_skeleton()));
  const std::optional<FittedShape> mixed = rough_shape_from({camera_bent_elbow_skeleton(), controlled_pose_skeleton(),
                                                             camera_bent_elbow_skeleton(), controlled_pose_skeleton()});
  ASSERT_TRUE(straight_only && mixed);
  EXPECT_TRUE(mixed->beta.isApprox(straight_only->beta, 1e-12));
  EXPECT_FALSE(bent_only->beta.isApprox(straight_only->beta, 1e-3));
}

TEST(FitBodyTracker, NoCalibrationFramesNoShape) {
  BodyTracker tracker(female(), raycast::DepthIntrinsics{}, rough_shape_only());
  const BodyTracker::Admitted admitted = tracker.personalise_now();
  EXPECT_TRUE(admitted.frames.empty());
  EXPECT_TRUE(admitted.warnings.empty());
  EXPECT_FALSE(tracker.shape());
}

// A frame that cannot be fitted (here: an empty silhouette) is a warning; the tracker goes on.
TEST(FitBodyTracker, UnfittableFrameIsAWarning) {
  const raycast::DepthIntrinsics intrinsics{};
  BodyTrackerOptions options = rough_shape_only();
  options.calibration_s = 0;
  BodyTracker tracker(female(), intrinsics, options);
  tracker.record_frame_stats(true);
  BodyFitFrame frame = frame_at(0, controlled_pose_skeleton());
  frame.frame.width = intrinsics.width;
  frame.frame.height = intrinsics.height;
  frame.frame.depth_mm.assign(static_cast<std::size_t>(intrinsics.width * intrinsics.height), 0);
  frame.frame.body_index.assign(frame.frame.depth_mm.size(), kNoBody);
  BodyTracker::Admitted admitted = tracker.admit(std::move(frame));
  ASSERT_EQ(admitted.frames.size(), 1u);
  const BodyTracker::Output out = tracker.fit(admitted.frames[0], no_orientation);
  EXPECT_FALSE(out.fitted);
  EXPECT_TRUE(out.frames.empty());
  ASSERT_EQ(out.warnings.size(), 1u);
  EXPECT_EQ(out.warnings[0].code, "FIT_FRAME");
  EXPECT_NE(out.warnings[0].message.find("t_us=0"), std::string::npos);
  EXPECT_EQ(tracker.frames_fitted(), 0u);
  EXPECT_TRUE(tracker.frame_stats().empty());
  EXPECT_TRUE(tracker.flush(no_orientation).frames.empty());
}

// The knee's rotation relative to the hip, degrees.
double knee_rotation_deg(const FittedBodyFrame& f, int hip, int knee) {
  return Eigen::AngleAxisd(f.K_from_joint[hip].inverse() * f.K_from_joint[knee]).angle() * 180 / std::numbers::pi;
}

// A subject of the template shape with the left knee bent 60 degrees (thigh 40 forward), the right
// leg straight, rendered with its error-free camera skeleton; `left_ankle` is the camera's tracking
// of the left ankle. Returns the fitted frames of the calibration frame and one after it.
std::vector<FittedBodyFrame> fit_bent_left_leg(JointTracking left_ankle) {
  const PoseLayout layout = PoseLayout::full_body();
  const Eigen::VectorXd beta = Eigen::VectorXd::Zero(10);
  const Eigen::VectorXd theta = testing::facing_pose(
      layout, 3.0, {{"left_shoulder_z", -30}, {"right_shoulder_z", 30}, {"left_hip_x", -40}, {"left_knee_x", 60}});
  const raycast::DepthCamera camera{raycast::DepthIntrinsics{}};
  const testing::ModelFrame rendered = testing::render_model_frame(female(), layout, beta, theta, camera);
  TrackedSkeleton skeleton = TrackedSkeleton::all_tracked(rendered.skeleton_K);
  skeleton.tracking[kAnkleLeft] = left_ankle;
  BodyTrackerOptions options = rough_shape_only();
  options.calibration_s = 0.05;  // the first frame; its bent knee refuses the shape: the template
  options.smoothing.window_frames = 1;
  BodyTracker tracker(female(), camera.intrinsics(), options);
  std::vector<FittedBodyFrame> fitted;
  for (std::int64_t t : {0, 100'000}) {
    BodyFitFrame frame = frame_at(t, skeleton);
    frame.frame = rendered.frame;
    for (BodyFitFrame& admitted : tracker.admit(std::move(frame)).frames) {
      BodyTracker::Output out = tracker.fit(admitted, no_orientation);
      EXPECT_TRUE(out.warnings.empty()) << out.warnings.front().message;
      for (FittedBodyFrame& f : out.frames) fitted.push_back(std::move(f));
    }
  }
  for (FittedBodyFrame& f : tracker.flush(no_orientation).frames) fitted.push_back(std::move(f));
  EXPECT_FALSE(tracker.shape()->estimated);
  return fitted;
}

// The camera shows the left knee bent 60 degrees: that leg is fitted free and follows the depth;
// the straight right leg's knee is held at zero.
TEST(FitBodyTracker, BendsTheLegsTheCameraShowsBentAndHoldsTheOthersStraight) {
  const std::vector<FittedBodyFrame> fitted = fit_bent_left_leg(JointTracking::kTracked);
  ASSERT_EQ(fitted.size(), 2u);
  for (const FittedBodyFrame& f : fitted) {
    EXPECT_NEAR(knee_rotation_deg(f, body::kLeftHip, body::kLeftKnee), 60, 5) << f.t_us;
    EXPECT_LT(knee_rotation_deg(f, body::kRightHip, body::kRightKnee), 1e-6) << f.t_us;
  }
}

// An inferred ankle is the camera's guess: the leg stays straight as in paper 2's upper-body fit.
TEST(FitBodyTracker, AGuessedLegIsHeldStraight) {
  const std::vector<FittedBodyFrame> fitted = fit_bent_left_leg(JointTracking::kInferred);
  ASSERT_EQ(fitted.size(), 2u);
  for (const FittedBodyFrame& f : fitted) EXPECT_LT(knee_rotation_deg(f, body::kLeftHip, body::kLeftKnee), 1e-6);
}

}  // namespace
}  // namespace posefuse::fit
