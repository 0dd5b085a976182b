#include "fit/rough_shape.hpp"

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

const std::shared_ptr<body::SmplModel>& female() {
  static const std::shared_ptr<body::SmplModel> model = body::make_template(body::Sex::kFemale);
  return model;
}

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
  for (int s = 0; s < kBodySegmentCount; ++s) EXPECT_NEAR(r.model[s], truth[s], 0.005) << body_segment_name(BodySegment(s));
}

std::string refusal(const TrackedSkeleton& frame) {
  const TrackedSkeleton good = testing::pose_subject(*female(), PoseLayout::full_body(), true_shape(),
                                                     controlled_pose(PoseLayout::full_body())).skeleton;
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
  EXPECT_EQ(refusal(posed({{"left_elbow_y", -60}})), "calibration_frames[1].pose.left_elbow");
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

}  // namespace
}  // namespace posefuse::fit
