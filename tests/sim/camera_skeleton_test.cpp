#include "sim/camera_skeleton.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "body/template_generator.hpp"
#include "common/error.hpp"
#include "raycast/mesh_scene.hpp"
#include "test_camera.hpp"

using posefuse::Error;
using namespace posefuse::sim;
namespace body = posefuse::body;
namespace raycast = posefuse::raycast;
namespace v1 = posefuse::v1;

using posefuse::sim::testing::small_camera;

namespace {

using enum posefuse::geometry::KinectJoint;

using std::numbers::pi;
constexpr double kDeg = pi / 180.0;

// The template facing the camera 2.5 m away, arms lowered 40 deg, spine bent by `spine_deg`
// per spine joint; the body frame is K itself.
struct PosedScene {
  SmplJointsK joints;
  std::vector<uint16_t> depth_mm;
  std::vector<std::int32_t> face;
};

const body::SmplModel& template_model() { return *body::shared_template(body::Sex::kMale); }

PosedScene posed_scene(double spine_deg = 0.0, double yaw_deg = 0.0) {
  const auto model = body::shared_template(body::Sex::kMale);
  const body::PoseLayout layout = body::PoseLayout::all_joints();
  body::BodyEvaluator eval(model, layout);
  Eigen::VectorXd theta = layout.zero();
  theta[layout.index_of("pelvis_y")] = pi + yaw_deg * kDeg;
  theta[layout.index_of("translation_y")] = -0.95;
  theta[layout.index_of("translation_z")] = 2.5;
  theta[layout.index_of("left_shoulder_z")] = -40 * kDeg;
  theta[layout.index_of("right_shoulder_z")] = 40 * kDeg;
  for (const char* s : {"spine1_x", "spine2_x", "spine3_x"}) theta[layout.index_of(s)] = spine_deg * kDeg;
  eval.evaluate(Eigen::VectorXd::Zero(10), theta, body::Derivatives::kNone);
  raycast::MeshScene scene(raycast::EmbreeDevice::shared(), model->faces, model->num_vertices());
  scene.update_vertices(eval.vertices());
  raycast::RenderImages images;
  scene.render(small_camera(), 0, images);
  return {smpl_joints_in_camera(eval, Eigen::Isometry3d::Identity()), images.depth_mm, images.face};
}

CameraSkeletonOptions error_free() {
  CameraSkeletonOptions o;
  o.upper_limb_bias_min_m = o.upper_limb_bias_max_m = 0;
  o.other_bias_min_m = o.other_bias_max_m = 0;
  o.jitter_sigma_m = 0;
  o.inferred_error_m = 0;
  o.inferred_shoulder_drop_m = 0;
  o.jump_probability = 0;
  o.hand_flip_probability = 0;
  return o;
}

Eigen::Vector3d position(const v1::SkeletonFrame& f, int j) {
  const auto& p = f.joints(j).position_m();
  return {p.x(), p.y(), p.z()};
}

Eigen::Quaterniond orientation(const v1::SkeletonFrame& f, int j) {
  const auto& q = f.joints(j).orientation();
  return {q.w(), q.x(), q.y(), q.z()};
}

constexpr std::int64_t kFrameUs = 33333;

}  // namespace

TEST(CameraSkeleton, ErrorFreeFrameHasSdkStructure) {
  const PosedScene scene = posed_scene();
  const CameraSkeletonSimulator sim(small_camera(), error_free(), 1, template_model());
  const v1::SkeletonFrame f = sim.simulate(scene.joints, scene.depth_mm, scene.face, 0, 1000, 2);
  ASSERT_EQ(f.joints_size(), kCameraJointCount);
  EXPECT_EQ(f.t_us(), 1000);
  EXPECT_EQ(f.body_id(), 2u);
  const Eigen::Matrix3Xd truth = camera_joints_from_smpl(scene.joints);
  for (int j = 0; j < kCameraJointCount; ++j) {
    EXPECT_EQ(f.joints(j).state(), v1::SkeletonJoint::TRACKED) << "joint " << j;
    EXPECT_LT((position(f, j) - truth.col(j)).norm(), 1e-9) << "joint " << j;
    const Eigen::Quaterniond q = orientation(f, j);
    const bool end_joint = j == kHead || j == kFootLeft || j == kFootRight || j >= kHandTipLeft;
    EXPECT_NEAR(q.norm(), end_joint ? 0.0 : 1.0, 1e-9) << "joint " << j;
    if (!end_joint && j != kSpineBase) {
      // Hierarchical orientation: y along the bone from the parent.
      const int parent = camera_joint_parents()[j];
      const Eigen::Vector3d bone = (truth.col(j) - truth.col(parent)).normalized();
      EXPECT_LT((q.toRotationMatrix().col(1) - bone).norm(), 1e-9) << "joint " << j;
    }
  }
  // Facing the camera, the subject's left hand is on the camera's right: x_K < 0.
  EXPECT_LT(truth(0, kHandLeft), -0.3);
  EXPECT_GT(truth(0, kHandRight), 0.3);
  EXPECT_GT(truth(1, kHead), truth(1, kNeck) + 0.1);
}

TEST(CameraSkeleton, UpperLimbErrorWithinConfiguredBand) {
  const PosedScene scene = posed_scene();
  CameraSkeletonOptions options;
  options.jump_probability = 0;
  const CameraSkeletonSimulator sim(small_camera(), options, 17, template_model());
  const Eigen::Matrix3Xd truth = camera_joints_from_smpl(scene.joints);
  const int frames = 600;
  std::array<double, kCameraJointCount> sum_error{};
  for (int k = 0; k < frames; ++k) {
    const v1::SkeletonFrame f = sim.simulate(scene.joints, scene.depth_mm, scene.face, k, k * kFrameUs, 0);
    for (int j = 0; j < kCameraJointCount; ++j) {
      ASSERT_EQ(f.joints(j).state(), v1::SkeletonJoint::TRACKED) << "joint " << j;
      sum_error[j] += (position(f, j) - truth.col(j)).norm();
    }
  }
  double upper_sum = 0, other_sum = 0;
  int upper_count = 0, other_count = 0;
  const double slack = 2 * options.jitter_sigma_m;  // jitter lengthens a bias on average
  for (int j = 0; j < kCameraJointCount; ++j) {
    const double mean = sum_error[j] / frames;
    if (is_upper_limb(j)) {
      EXPECT_GE(mean, options.upper_limb_bias_min_m - slack) << "joint " << j;
      EXPECT_LE(mean, options.upper_limb_bias_max_m + slack) << "joint " << j;
      upper_sum += mean;
      ++upper_count;
    } else {
      EXPECT_GE(mean, options.other_bias_min_m - slack) << "joint " << j;
      EXPECT_LE(mean, options.other_bias_max_m + slack) << "joint " << j;
      other_sum += mean;
      ++other_count;
    }
  }
  std::printf("mean joint error: upper limb %.1f mm (band %.0f-%.0f), others %.1f mm (band %.0f-%.0f)\n",
              1000 * upper_sum / upper_count, 1000 * options.upper_limb_bias_min_m,
              1000 * options.upper_limb_bias_max_m, 1000 * other_sum / other_count, 1000 * options.other_bias_min_m,
              1000 * options.other_bias_max_m);
}

TEST(CameraSkeleton, OccludedJointsAreInferredWithLargerError) {
  PosedScene scene = posed_scene();
  // A board 1.5 m from the camera covers the right part of the image (the subject's left side).
  const raycast::DepthCamera camera = small_camera();
  for (int row = 0; row < camera.height(); ++row) {
    for (int col = 68; col < camera.width(); ++col)
      scene.depth_mm[static_cast<std::size_t>(row) * camera.width() + col] = 1500;
  }
  const Eigen::Matrix3Xd truth = camera_joints_from_smpl(scene.joints);
  const CameraSkeletonSimulator sim(camera, CameraSkeletonOptions{}, 5, template_model());
  std::array<int, kCameraJointCount> inferred_frames{};
  double inferred_error = 0, tracked_error = 0;
  int inferred_count = 0, tracked_count = 0;
  for (int k = 0; k < 300; ++k) {
    const v1::SkeletonFrame f = sim.simulate(scene.joints, scene.depth_mm, scene.face, k, k * kFrameUs, 0);
    for (int j = 0; j < kCameraJointCount; ++j) {
      const bool inferred = f.joints(j).state() == v1::SkeletonJoint::INFERRED;
      inferred_frames[j] += inferred;
      const double e = (position(f, j) - truth.col(j)).norm();
      if (!is_upper_limb(j)) continue;
      (inferred ? inferred_error : tracked_error) += e;
      (inferred ? inferred_count : tracked_count) += 1;
    }
  }
  for (int j : {kShoulderLeft, kElbowLeft, kWristLeft, kHandLeft, kHandTipLeft})
    EXPECT_EQ(inferred_frames[j], 300) << j;
  for (int j : {kShoulderRight, kElbowRight, kWristRight, kHandRight, kHandTipRight, kHead}) {
    EXPECT_EQ(inferred_frames[j], 0) << j;
  }
  ASSERT_GT(inferred_count, 0);
  ASSERT_GT(tracked_count, 0);
  std::printf("upper-limb mean error: inferred %.1f mm, tracked %.1f mm\n", 1000 * inferred_error / inferred_count,
              1000 * tracked_error / tracked_count);
  EXPECT_GT(inferred_error / inferred_count, tracked_error / tracked_count + 0.02);

  // An inferred shoulder is lowered.
  CameraSkeletonOptions drop_only = error_free();
  drop_only.inferred_shoulder_drop_m = 0.05;
  const v1::SkeletonFrame f = CameraSkeletonSimulator(camera, drop_only, 5, template_model())
                                  .simulate(scene.joints, scene.depth_mm, scene.face, 0, 0, 0);
  EXPECT_NEAR(position(f, kShoulderLeft).y(), truth(1, kShoulderLeft) - 0.05, 1e-9);
  EXPECT_NEAR(position(f, kShoulderRight).y(), truth(1, kShoulderRight), 1e-9);
}

TEST(CameraSkeleton, FarArmOfSideViewIsInferred) {
  // Turned 90 deg, the subject's right side faces the camera; the left arm is behind the torso.
  const PosedScene scene = posed_scene(0.0, 90.0);
  const Eigen::Matrix3Xd truth = camera_joints_from_smpl(scene.joints);
  ASSERT_GT(truth(2, kElbowLeft), truth(2, kElbowRight) + 0.3);
  const v1::SkeletonFrame f = CameraSkeletonSimulator(small_camera(), error_free(), 2, template_model())
                                  .simulate(scene.joints, scene.depth_mm, scene.face, 0, 0, 0);
  for (int j : {kElbowLeft, kWristLeft, kHandLeft}) EXPECT_EQ(f.joints(j).state(), v1::SkeletonJoint::INFERRED) << j;
  for (int j : {kShoulderRight, kElbowRight, kWristRight, kHandRight, kHead}) {
    EXPECT_EQ(f.joints(j).state(), v1::SkeletonJoint::TRACKED) << j;
  }
}

TEST(CameraSkeleton, JumpRateNearConfigured) {
  const PosedScene scene = posed_scene();
  CameraSkeletonOptions with_jumps;
  with_jumps.jump_probability = 0.03;
  CameraSkeletonOptions without = with_jumps;
  without.jump_probability = 0;
  const CameraSkeletonSimulator a(small_camera(), with_jumps, 9, template_model()),
      b(small_camera(), without, 9, template_model());
  const int frames = 3000;
  int jumped_frames = 0;
  for (int k = 0; k < frames; ++k) {
    const v1::SkeletonFrame fa = a.simulate(scene.joints, scene.depth_mm, scene.face, k, k * kFrameUs, 0);
    const v1::SkeletonFrame fb = b.simulate(scene.joints, scene.depth_mm, scene.face, k, k * kFrameUs, 0);
    int moved = 0;
    for (int j = 0; j < kCameraJointCount; ++j) {
      const double d = (position(fa, j) - position(fb, j)).norm();
      if (d == 0) continue;
      ++moved;
      EXPECT_TRUE(is_upper_limb(j)) << j;
      EXPECT_GE(d, with_jumps.jump_min_m - 1e-9);
      EXPECT_LE(d, with_jumps.jump_max_m + 1e-9);
    }
    EXPECT_LE(moved, 1);
    jumped_frames += moved;
  }
  const double rate = static_cast<double>(jumped_frames) / frames;
  std::printf("jump rate %.4f over %d frames (configured %.3f)\n", rate, frames, with_jumps.jump_probability);
  EXPECT_NEAR(rate, with_jumps.jump_probability, 0.01);  // binomial sd 0.0031
}

TEST(CameraSkeleton, HandOrientationSometimesFlipped) {
  const PosedScene scene = posed_scene();
  CameraSkeletonOptions flips = error_free();
  flips.hand_flip_probability = 0.05;
  const CameraSkeletonSimulator a(small_camera(), flips, 4, template_model()),
      b(small_camera(), error_free(), 4, template_model());
  int flipped = 0, hands = 0;
  for (int k = 0; k < 2000; ++k) {
    const v1::SkeletonFrame fa = a.simulate(scene.joints, scene.depth_mm, scene.face, k, k * kFrameUs, 0);
    const v1::SkeletonFrame fb = b.simulate(scene.joints, scene.depth_mm, scene.face, k, k * kFrameUs, 0);
    for (int j : {kHandLeft, kHandRight}) {
      ++hands;
      const Eigen::Quaterniond qa = orientation(fa, j), qb = orientation(fb, j);
      const double angle = qa.angularDistance(qb);
      if (angle < 1e-9) continue;
      ++flipped;
      EXPECT_NEAR(angle, pi, 1e-6);
      // About the bone: the y axis stays.
      EXPECT_LT((qa.toRotationMatrix().col(1) - qb.toRotationMatrix().col(1)).norm(), 1e-9);
    }
  }
  const double rate = static_cast<double>(flipped) / hands;
  std::printf("hand flip rate %.4f (configured %.3f)\n", rate, flips.hand_flip_probability);
  EXPECT_NEAR(rate, flips.hand_flip_probability, 0.015);
}

TEST(CameraSkeleton, TrunkJointsAreHiddenOnlyByAnotherPart) {
  const PosedScene scene = posed_scene();
  const Eigen::Matrix3Xd truth = camera_joints_from_smpl(scene.joints);
  // No margin: every joint's own surface lies in front of it. The trunk's own surface does not
  // hide a trunk joint; a limb joint has only the depth rule.
  CameraSkeletonOptions no_margin = error_free();
  no_margin.occlusion_margin_m = 0;
  const CameraSkeletonSimulator sim(small_camera(), no_margin, 6, template_model());
  const v1::SkeletonFrame f = sim.simulate(scene.joints, scene.depth_mm, scene.face, 0, 0, 0);
  for (int j : {kSpineBase, kSpineMid, kSpineShoulder, kHipLeft, kHipRight}) {
    EXPECT_EQ(f.joints(j).state(), v1::SkeletonJoint::TRACKED) << j;
  }
  for (int j : {kElbowLeft, kElbowRight}) EXPECT_EQ(f.joints(j).state(), v1::SkeletonJoint::INFERRED) << j;

  // A hand held 20 cm in front of SpineMid: another part, which hides it.
  int hand_face = -1;
  for (int face = 0; face < template_model().num_faces() && hand_face < 0; ++face) {
    if (body::dominant_joint(template_model(), template_model().faces(0, face)) == body::kLeftWrist) hand_face = face;
  }
  ASSERT_GE(hand_face, 0);
  const raycast::DepthCamera camera = small_camera();
  const Eigen::Vector2d uv = *camera.project(truth.col(kSpineMid));
  PosedScene covered = scene;
  for (int row = static_cast<int>(uv.y()) - 3; row <= static_cast<int>(uv.y()) + 3; ++row) {
    for (int col = static_cast<int>(uv.x()) - 3; col <= static_cast<int>(uv.x()) + 3; ++col) {
      const auto pixel = static_cast<std::size_t>(row) * camera.width() + col;
      covered.depth_mm[pixel] = static_cast<uint16_t>(std::lround(1000 * (truth(2, kSpineMid) - 0.2)));
      covered.face[pixel] = hand_face;
    }
  }
  const CameraSkeletonSimulator standard(small_camera(), error_free(), 6, template_model());
  EXPECT_EQ(standard.simulate(scene.joints, scene.depth_mm, scene.face, 0, 0, 0).joints(kSpineMid).state(),
            v1::SkeletonJoint::TRACKED);
  EXPECT_EQ(standard.simulate(covered.joints, covered.depth_mm, covered.face, 0, 0, 0).joints(kSpineMid).state(),
            v1::SkeletonJoint::INFERRED);
}

TEST(CameraSkeleton, SpineStaysStraightWhenBent) {
  const PosedScene scene = posed_scene(15.0);
  const Eigen::Matrix3Xd truth = camera_joints_from_smpl(scene.joints);
  const Eigen::Vector3d base = truth.col(kSpineBase), top = truth.col(kSpineShoulder);
  auto off_line_m = [&](const Eigen::Vector3d& p) { return (p - base).cross((top - base).normalized()).norm(); };
  const v1::SkeletonFrame f = CameraSkeletonSimulator(small_camera(), error_free(), 3, template_model())
                                  .simulate(scene.joints, scene.depth_mm, scene.face, 0, 0, 0);
  std::printf("bent spine: SMPL spine2 %.1f mm off the base-shoulder line, reported SpineMid %.3f mm\n",
              1000 * off_line_m(truth.col(kSpineMid)), 1000 * off_line_m(position(f, kSpineMid)));
  EXPECT_GT(off_line_m(truth.col(kSpineMid)), 0.01);
  EXPECT_LT(off_line_m(position(f, kSpineMid)), 1e-6);
}

TEST(CameraSkeleton, DeterministicForSeedAndFrame) {
  const PosedScene scene = posed_scene();
  const CameraSkeletonSimulator a(small_camera(), CameraSkeletonOptions{}, 8, template_model()),
      b(small_camera(), CameraSkeletonOptions{}, 8, template_model());
  const CameraSkeletonSimulator c(small_camera(), CameraSkeletonOptions{}, 9, template_model());
  const std::string fa = a.simulate(scene.joints, scene.depth_mm, scene.face, 5, 5 * kFrameUs, 0).SerializeAsString();
  EXPECT_EQ(fa, b.simulate(scene.joints, scene.depth_mm, scene.face, 5, 5 * kFrameUs, 0).SerializeAsString());
  EXPECT_NE(fa, a.simulate(scene.joints, scene.depth_mm, scene.face, 6, 5 * kFrameUs, 0).SerializeAsString());
  EXPECT_NE(fa, c.simulate(scene.joints, scene.depth_mm, scene.face, 5, 5 * kFrameUs, 0).SerializeAsString());
}

TEST(CameraSkeleton, RejectsBadInput) {
  const PosedScene scene = posed_scene();
  CameraSkeletonOptions bad;
  bad.upper_limb_bias_max_m = 0.01;  // below the minimum
  EXPECT_THROW(CameraSkeletonSimulator(small_camera(), bad, 1, template_model()), Error);
  bad = CameraSkeletonOptions{};
  bad.jump_probability = 2;
  EXPECT_THROW(validate(bad), Error);
  bad = CameraSkeletonOptions{};
  bad.down_K = Eigen::Vector3d(0, 0, 0);
  EXPECT_THROW(validate(bad), Error);
  const CameraSkeletonSimulator sim(small_camera(), CameraSkeletonOptions{}, 1, template_model());
  std::vector<uint16_t> short_depth(scene.depth_mm.begin(), scene.depth_mm.end() - 1);
  EXPECT_THROW(sim.simulate(scene.joints, short_depth, scene.face, 0, 0, 0), Error);
  std::vector<std::int32_t> short_face(scene.face.begin(), scene.face.end() - 1);
  EXPECT_THROW(sim.simulate(scene.joints, scene.depth_mm, short_face, 0, 0, 0), Error);
  std::vector<std::int32_t> foreign_face = scene.face;
  foreign_face[foreign_face.size() / 2] = template_model().num_faces();  // a face of some other mesh
  EXPECT_THROW(sim.simulate(scene.joints, scene.depth_mm, foreign_face, 0, 0, 0), Error);
  SmplJointsK nan_joints = scene.joints;
  nan_joints.positions_K(0, 3) = std::nan("");
  EXPECT_THROW(sim.simulate(nan_joints, scene.depth_mm, scene.face, 0, 0, 0), Error);
}
