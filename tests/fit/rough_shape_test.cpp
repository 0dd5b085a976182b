#include "fit/rough_shape.hpp"

#include "fit/personalisation.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <random>

#include "body/template_generator.hpp"
#include "posed_subject.hpp"
#include "synthetic_frames.hpp"

namespace posefuse::fit {
namespace {

using body::PoseLayout;

const std::shared_ptr<body::SmplModel>& female() { return testing::template_model(body::Sex::kFemale); }

Eigen::VectorXd true_shape() {
  Eigen::VectorXd beta = Eigen::VectorXd::Zero(10);
  // stature, torso, legs, upper arm, forearm, shoulders, hips, torso girth, limb girth, head
  beta << 0.8, -0.5, 0.6, 1.0, -0.7, 0.6, 0.4, 0.5, -0.3, 0.5;
  return beta;
}

// The controlled pose: facing the camera at 3.2 m, arms straight and held 60 degrees from the trunk.
Eigen::VectorXd controlled_pose(const PoseLayout& layout) {
  return testing::facing_pose(layout, 3.2, {{"left_shoulder_z", -30}, {"right_shoulder_z", 30}});
}

const raycast::DepthCamera& kinect() {
  static const raycast::DepthCamera camera{raycast::DepthIntrinsics{}};
  return camera;
}

TEST(FitRoughShape, RecoversTheSegmentsAndIdentifiableBetasOfAKnownShape) {
  const PoseLayout layout = PoseLayout::full_body();
  const testing::PosedSubject subject = testing::pose_subject(*female(), layout, true_shape(), controlled_pose(layout));
  const RoughShapeResult r = estimate_rough_shape(*female(), {subject.skeleton}, &kinect());
  EXPECT_NE(r.stop, RoughShapeStop::kMaxIterations);
  const SegmentLengths truth = ModelSegmentLengths(*female(), 0.09).lengths(true_shape());
  for (int s = 0; s < kBodySegmentCount; ++s) {
    EXPECT_NEAR(r.measured[s], truth[s], 1e-9) << body_segment_name(BodySegment(s));
    EXPECT_NEAR(r.model[s], truth[s], 1e-3) << body_segment_name(BodySegment(s));
  }
  EXPECT_LT(r.energy, 1e-3 * r.initial_energy);
  // Hip width and the girths move no joint distance the 7 measurements see.
  EXPECT_EQ(r.unconstrained_betas, (std::vector<int>{6, 7, 8}));
  for (int b : {6, 7, 8}) EXPECT_NEAR(r.beta[b], 0.0, 1e-9);
  // Stature, torso, legs, arms, shoulders and head are pinned by the 7 measurements.
  for (int b : {0, 1, 2, 3, 4, 5, 9}) EXPECT_NEAR(r.beta[b], true_shape()[b], 1e-3) << "beta " << b;
}

TEST(FitRoughShape, AveragesNoisyFrames) {
  const PoseLayout layout = PoseLayout::full_body();
  const testing::PosedSubject subject = testing::pose_subject(*female(), layout, true_shape(), controlled_pose(layout));
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 0.005);
  std::vector<TrackedSkeleton> frames(60, subject.skeleton);
  for (auto& f : frames)
    for (auto& p : f.positions_K) p += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  const RoughShapeResult r = estimate_rough_shape(*female(), frames, &kinect());
  const SegmentLengths truth = ModelSegmentLengths(*female(), 0.09).lengths(true_shape());
  for (int s = 0; s < kBodySegmentCount; ++s)
    EXPECT_NEAR(r.model[s], truth[s], 0.005) << body_segment_name(BodySegment(s));
}

// Camera-skeleton biases can ask for a shape outside the model's range: betas stop at the bound.
TEST(FitRoughShape, BetasStayWithinTheirBound) {
  const PoseLayout layout = PoseLayout::full_body();
  TrackedSkeleton frame = testing::pose_subject(*female(), layout, true_shape(), controlled_pose(layout)).skeleton;
  for (const auto& [shoulder, elbow] : {std::pair{kShoulderLeft, kElbowLeft}, std::pair{kShoulderRight, kElbowRight}}) {
    const Eigen::Vector3d upper = frame.positions_K[elbow] - frame.positions_K[shoulder];
    frame.positions_K[elbow] -= 0.12 * upper.normalized();  // upper arms 12 cm too short
  }
  const RoughShapeResult r = estimate_rough_shape(*female(), {frame}, &kinect());
  EXPECT_EQ(r.beta[3], -3.0);  // upper_arm_length at its bound
  EXPECT_LE(r.beta.cwiseAbs().maxCoeff(), 3.0);
  EXPECT_NE(r.stop, RoughShapeStop::kMaxIterations);
}

std::string refusal(const TrackedSkeleton& frame) {
  const TrackedSkeleton good =
      testing::pose_subject(*female(), PoseLayout::full_body(), true_shape(), controlled_pose(PoseLayout::full_body()))
          .skeleton;
  return testing::error_field([&] { estimate_rough_shape(*female(), {good, frame}, &kinect()); });
}

TEST(FitRoughShape, RefusesWhenNotInThePoseOrNotInView) {
  const PoseLayout layout = PoseLayout::full_body();
  auto posed = [&](std::initializer_list<std::pair<const char*, double>> extra, double depth = 3.2) {
    Eigen::VectorXd theta = controlled_pose(layout);
    const Eigen::VectorXd change = testing::facing_pose(layout, 0, extra) - testing::facing_pose(layout, 0, {});
    theta += change;
    theta[layout.index_of("translation_z")] = depth;
    return testing::pose_subject(*female(), layout, true_shape(), theta).skeleton;
  };
  EXPECT_EQ(refusal(posed({{"left_elbow_y", -80}})), "calibration_frames[1].pose.left_elbow");
  EXPECT_EQ(refusal(posed({{"right_knee_x", 50}})), "calibration_frames[1].pose.right_knee");
  EXPECT_EQ(refusal(posed({{"left_shoulder_z", -55}})), "calibration_frames[1].pose.left_arm");  // arm hangs down
  EXPECT_EQ(refusal(posed({{"pelvis_y", 50}})), "calibration_frames[1].pose.facing");
  EXPECT_EQ(refusal(posed({}, 1.4)), "calibration_frames[1].AnkleLeft");  // too close: the feet leave the image
  TrackedSkeleton inferred = posed({});
  inferred.tracking[kKneeRight] = JointTracking::kInferred;
  EXPECT_EQ(refusal(inferred), "calibration_frames[1].KneeRight");
  TrackedSkeleton nan_head = posed({});
  nan_head.positions_K[kHead].x() = std::nan("");
  EXPECT_EQ(refusal(nan_head), "calibration_frames[1].Head");
  EXPECT_EQ(testing::error_field([&] { estimate_rough_shape(*female(), {}, &kinect()); }), "calibration_frames");
  RoughShapeOptions bad;
  bad.min_step = 0;
  EXPECT_EQ(testing::error_field([&] { estimate_rough_shape(*female(), {posed({})}, nullptr, bad); }),
            "rough_options.min_step");
}

TEST(FitRoughShape, AnElbowMayLookAsBentAsTheCamerasArmJointErrorAllows) {
  // 55 degrees: past the pose's 40, within the ~21 that 5 cm of camera error across the elbow
  // adds on this arm; refused when the camera is taken as exact.
  const PoseLayout layout = PoseLayout::full_body();
  Eigen::VectorXd theta = controlled_pose(layout);
  theta += testing::facing_pose(layout, 0, {{"right_elbow_y", 55}}) - testing::facing_pose(layout, 0, {});
  const TrackedSkeleton bent = testing::pose_subject(*female(), layout, true_shape(), theta).skeleton;
  EXPECT_NO_THROW(check_controlled_pose({bent}, &kinect()));
  ControlledPoseLimits exact_camera;
  exact_camera.camera_arm_joint_error_m = 0;
  EXPECT_EQ(testing::error_field([&] { check_controlled_pose({bent}, &kinect(), exact_camera); }),
            "calibration_frames[0].pose.right_elbow");
  ControlledPoseLimits bad;
  bad.camera_arm_joint_error_m = -0.01;
  EXPECT_EQ(testing::error_field([&] { check_controlled_pose({bent}, &kinect(), bad); }),
            "pose_limits.camera_arm_joint_error_m");
}

// The fine-tuning seam: the refiner gets the rough shape and a full-body pose built from the chosen
// frame, and its result becomes the subject's shape. (The refiner here only records its inputs;
// the real one is the LM fitter with the shape free.)
TEST(FitPersonalisation, FineTuningSeamGetsTheRoughShapeAndAFullBodyStart) {
  const PoseLayout layout = PoseLayout::full_body();
  const testing::PosedSubject subject = testing::pose_subject(*female(), layout, true_shape(), controlled_pose(layout));
  const std::vector<TrackedSkeleton> frames(5, subject.skeleton);

  const Personalisation rough_only = personalise(female(), frames, &kinect(), nullptr);
  EXPECT_FALSE(rough_only.fine_tuned);
  EXPECT_EQ(rough_only.beta(), rough_only.rough.beta);
  EXPECT_EQ(rough_only.fine_tune_frame, 2u);
  for (int s = 0; s < kBodySegmentCount; ++s)
    EXPECT_NEAR(rough_only.segment_lengths[s], rough_only.rough.measured[s], 1e-3);

  std::size_t seen_frame = 99;
  Eigen::VectorXd seen_beta, seen_theta;
  Eigen::VectorXd refined_beta = true_shape();
  const ShapePoseRefiner refiner = [&](std::size_t frame, const Eigen::VectorXd& beta0, const Eigen::VectorXd& theta0) {
    seen_frame = frame;
    seen_beta = beta0;
    seen_theta = theta0;
    return ShapePoseFit{refined_beta, theta0, 1.5};
  };
  PersonalisationOptions options;
  options.fine_tune_frame = 4;
  const Personalisation p = personalise(female(), frames, &kinect(), refiner, options);
  EXPECT_EQ(seen_frame, 4u);
  EXPECT_EQ(seen_beta, p.rough.beta);
  ASSERT_EQ(seen_theta.size(), layout.size());
  const JointPose start = pose_joints(rest_joints(*female(), p.rough.beta), layout, seen_theta);
  for (int j = 0; j < body::kNumJoints; ++j)
    EXPECT_LT((start.positions_K.col(j) - subject.joints.positions_K.col(j)).norm(), 0.02)
        << body::smpl_joint_names()[j];
  EXPECT_TRUE(p.fine_tuned);
  EXPECT_EQ(p.beta(), refined_beta);
  EXPECT_EQ(p.fine.energy, 1.5);

  refined_beta[3] = std::nan("");
  EXPECT_EQ(testing::error_field([&] { personalise(female(), frames, &kinect(), refiner); }), "fine_tuning.beta");
  options.fine_tune_frame = 5;
  EXPECT_EQ(testing::error_field([&] { personalise(female(), frames, &kinect(), nullptr, options); }),
            "personalisation_options.fine_tune_frame");
}

}  // namespace
}  // namespace posefuse::fit
