#include "sim/bvh_retarget.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "common/error.hpp"
#include "sim/bvh_motion.hpp"
#include "sim/forearm_strap.hpp"
#include "sim/skeleton_pose.hpp"
#include "test_rigs.hpp"

using posefuse::Error;
using namespace posefuse::sim;
using posefuse::sim::testing::rig21;
using posefuse::sim::testing::rig_cmu31;
using posefuse::sim::testing::rig_text;
using posefuse::sim::testing::RigJointSpec;
namespace body = posefuse::body;

namespace {

using std::numbers::pi;
constexpr double kFrameTime = 1.0 / 60;

// Random poses: every rotation channel within +-35 deg, the root turned anywhere about the
// vertical, tilted up to 20 deg, and wandering by tens of cm.
std::string random_clip(const std::vector<RigJointSpec>& rig, int frames, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> joint(-35.0, 35.0), tilt(-20.0, 20.0), yaw(-180.0, 180.0), shift(-30.0, 30.0);
  std::vector<std::vector<double>> values;
  for (int f = 0; f < frames; ++f) {
    for (std::size_t j = 0; j < rig.size(); ++j) {
      if (rig[j].root) {
        values.push_back({shift(rng), 95.0 + 0.2 * shift(rng), shift(rng), tilt(rng), yaw(rng), tilt(rng)});
      } else {
        values.push_back({joint(rng), joint(rng), joint(rng)});
      }
    }
  }
  const std::size_t joints = rig.size();
  return rig_text(rig, frames, kFrameTime, [&](int f, int j, int c) {
    return values[static_cast<std::size_t>(f) * joints + static_cast<std::size_t>(j)][static_cast<std::size_t>(c)];
  });
}

double angle_deg(const Vec3& a, const Vec3& b) { return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / pi; }

// Largest angle over every frame and every mapped SMPL bone between the retargeted model's bone
// and the BVH's (placed in R), at the frame times.
double max_bone_error_deg(const BvhClip& clip, int* bones_checked = nullptr) {
  BvhMotionOptions options;
  options.smoothing_s = 0.0;
  BvhPlacement place;
  const BodyMotion motion = bvh_motion(clip, options, &place);
  const Eigen::Matrix3Xd rest = template_rest_joints(options.sex, options.betas);
  const BvhRetargetMap map = make_bvh_retarget_map(clip.skeleton, rest);
  double worst = 0.0;
  int bones = 0;
  for (int f = 0; f < clip.frame_count(); ++f) {
    const SkeletonPose pose = pose_skeleton(rest, body::PoseLayout::all_joints(), motion.poses(f * clip.frame_time_s));
    const std::vector<Vec3> p = bvh_joint_positions(clip.skeleton, clip.frames[static_cast<std::size_t>(f)]);
    bones = 0;
    for (int j = 0; j < body::kNumJoints; ++j) {
      const int c = map.aim_joint[static_cast<std::size_t>(j)];
      if (c < 0) continue;
      // The pelvis turns with the hips segment alone; its bone to the spine is the BVH's only
      // when the spine joint is a direct child (not through CMU's zero-length LowerBack, whose
      // bend goes into spine1).
      const int aimed = map.bvh_joint[static_cast<std::size_t>(c)];
      if (!map.aim_posed[static_cast<std::size_t>(j)] &&
          clip.skeleton.joints[static_cast<std::size_t>(aimed)].parent != map.bvh_joint[static_cast<std::size_t>(j)]) {
        continue;
      }
      const Vec3 model = pose.joints.col(c) - pose.joints.col(j);
      const Vec3 bvh = place.R_from_bvh * (p[static_cast<std::size_t>(map.bvh_joint[static_cast<std::size_t>(c)])] -
                                           p[static_cast<std::size_t>(map.bvh_joint[static_cast<std::size_t>(j)])]);
      worst = std::max(worst, angle_deg(model, bvh));
      ++bones;
    }
  }
  if (bones_checked) *bones_checked = bones;
  return worst;
}

void expect_rejected(const std::string& text, const std::string& needle) {
  const BvhClip clip = parse_bvh(text);
  try {
    bvh_motion(clip);
    ADD_FAILURE() << "not rejected";
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "bvh.joints");
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

}  // namespace

TEST(BvhRetarget, MapsBothRigsByName) {
  const Eigen::Matrix3Xd rest = template_rest_joints(body::Sex::kMale, Eigen::VectorXd::Zero(10));
  const BvhClip a = parse_bvh(random_clip(rig21(), 2, 1));
  const BvhRetargetMap m21 = make_bvh_retarget_map(a.skeleton, rest);
  auto name = [](const BvhClip& clip, const BvhRetargetMap& m, int j) {
    const int b = m.bvh_joint[static_cast<std::size_t>(j)];
    return b < 0 ? std::string("-") : clip.skeleton.joints[static_cast<std::size_t>(b)].name;
  };
  EXPECT_EQ(name(a, m21, body::kSpine1), "Spine");
  EXPECT_EQ(name(a, m21, body::kSpine2), "Spine1");
  EXPECT_EQ(name(a, m21, body::kSpine3), "-");
  EXPECT_EQ(name(a, m21, body::kNeck), "Neck1");
  EXPECT_EQ(name(a, m21, body::kRightElbow), "RightForeArm");
  EXPECT_EQ(m21.aim_joint[body::kSpine2], body::kNeck);  // aims past the unmapped spine3
  const BvhClip b = parse_bvh(random_clip(rig_cmu31(), 2, 2));
  const BvhRetargetMap m31 = make_bvh_retarget_map(b.skeleton, rest);
  EXPECT_EQ(name(b, m31, body::kSpine1), "LowerBack");
  EXPECT_EQ(name(b, m31, body::kSpine2), "Spine");
  EXPECT_EQ(name(b, m31, body::kSpine3), "Spine1");
  EXPECT_EQ(name(b, m31, body::kLeftHip), "LeftUpLeg");
  EXPECT_EQ(name(b, m31, body::kLeftHand), "-");
  // LowerBack has zero length: the pelvis aims at spine2 (Spine).
  EXPECT_EQ(m31.aim_joint[body::kPelvis], body::kSpine2);
  EXPECT_GT(m21.leg_length_ratio, 0.005);  // cm rig onto a metre model: about 0.0088
  EXPECT_LT(m21.leg_length_ratio, 0.012);
}

TEST(BvhRetarget, BoneDirectionsMatchTheBvh21) {
  int bones = 0;
  const double worst = max_bone_error_deg(parse_bvh(random_clip(rig21(), 40, 3)), &bones);
  // Pelvis, 2 x (hip, knee, ankle, collar, shoulder, elbow), spine1, spine2 (-> neck), neck;
  // the wrists have no mapped joint below (the hands' End Sites are at the wrist).
  EXPECT_EQ(bones, 16);
  EXPECT_LT(worst, 0.01) << "worst bone direction error, degrees";
}

TEST(BvhRetarget, BoneDirectionsMatchTheBvhCmu31) {
  int bones = 0;
  const double worst = max_bone_error_deg(parse_bvh(random_clip(rig_cmu31(), 40, 4)), &bones);
  EXPECT_EQ(bones, 16);  // as the 21-joint rig, plus spine3, minus the pelvis (see above)
  EXPECT_LT(worst, 0.01) << "worst bone direction error, degrees";
}

// Only RightForeArm's roll channel (its bone runs along the rig's x) moves: the model's forearm
// turns about its own axis by the same angle, the elbow and wrist stay put.
TEST(BvhRetarget, ForearmRollComesFromTheBvh) {
  const auto rig = rig21();
  const int forearm = 19;
  ASSERT_EQ(rig[forearm].name, "RightForeArm");
  const double roll_deg = 50.0;
  const BvhClip clip = parse_bvh(rig_text(rig, 2, kFrameTime, [&](int f, int j, int c) {
    if (rig[static_cast<std::size_t>(j)].root) return c == 1 ? 95.0 : 0.0;
    return (f == 1 && j == forearm && c == 2) ? roll_deg : 0.0;  // channel 2 = Xrotation
  }));
  BvhMotionOptions options;
  options.smoothing_s = 0.0;
  const BodyMotion motion = bvh_motion(clip, options);
  const Eigen::Matrix3Xd rest = template_rest_joints(options.sex, options.betas);
  const Quat rest_F = forearm_rest_R_from_F(rest, BodySide::kRight);
  const ForearmStrap strap;
  const auto at = [&](double t) {
    return forearm_pose(pose_skeleton(rest, body::PoseLayout::all_joints(), motion.poses(t)), rest_F, strap);
  };
  const ForearmPose before = at(0.0), after = at(kFrameTime);
  EXPECT_LT((before.elbow_R_m - after.elbow_R_m).norm(), 1e-9);
  EXPECT_LT((before.wrist_R_m - after.wrist_R_m).norm(), 1e-9);
  const Eigen::AngleAxisd turn(before.R_from_F.conjugate() * after.R_from_F);
  EXPECT_NEAR(turn.angle() * 180.0 / pi, roll_deg, 1e-6);
  EXPECT_NEAR(std::abs(turn.axis().y()), 1.0, 1e-9);         // about F's y: the forearm axis
  EXPECT_GT((before.imu_R_m - after.imu_R_m).norm(), 0.02);  // the IMU on the strap rolls along
}

TEST(BvhRetarget, PlacesTheClipOnTheFloorFacingFront) {
  const BvhClip clip = parse_bvh(random_clip(rig_cmu31(), 30, 5));
  BvhMotionOptions options;
  options.smoothing_s = 0.0;  // the random frames are uncorrelated; smoothing would move frame 0
  const BodyMotion motion = bvh_motion(clip, options);
  const Eigen::Matrix3Xd rest = template_rest_joints(options.sex, options.betas);
  EXPECT_NEAR(motion.duration_s, 29 * clip.frame_time_s, 1e-12);
  double lowest = 1e9;
  for (int f = 0; f < clip.frame_count(); ++f) {
    const SkeletonPose pose = pose_skeleton(rest, body::PoseLayout::all_joints(), motion.poses(f * clip.frame_time_s));
    for (int j : {body::kLeftAnkle, body::kRightAnkle, body::kLeftFoot, body::kRightFoot}) {
      lowest = std::min(lowest, pose.joints(1, j));
    }
    if (f == 0) {
      EXPECT_NEAR(pose.joints(0, body::kPelvis), 0.0, 1e-9);
      EXPECT_NEAR(pose.joints(2, body::kPelvis), 0.0, 1e-9);
      const Vec3 front = pose.rotation[body::kPelvis] * Vec3::UnitZ();
      EXPECT_NEAR(front.x(), 0.0, 1e-9);
      EXPECT_GT(front.z(), 0.0);
    }
  }
  const double rest_lowest = std::min({rest(1, body::kLeftAnkle), rest(1, body::kLeftFoot)});
  EXPECT_NEAR(lowest, rest_lowest, 1e-9);
  // Deterministic.
  const BodyMotion again = bvh_motion(clip, options);
  for (double t = 0; t < motion.duration_s; t += 0.01) EXPECT_EQ(motion.poses(t), again.poses(t));
}

TEST(BvhRetarget, RejectsMissingJointsAndBrokenHierarchies) {
  auto rig = rig21();
  const auto zero = [](int, int, int) { return 0.0; };
  rig[15].name = "LeftLowerThing";  // LeftForeArm
  expect_rejected(rig_text(rig, 2, kFrameTime, zero), "left_elbow");
  rig = rig21();
  rig[16].parent = 10;  // LeftHand hangs from Spine1 instead of the forearm
  expect_rejected(rig_text(rig, 2, kFrameTime, zero), "not below");
  rig = rig21();
  rig[0].name = "Torso";
  expect_rejected(rig_text(rig, 2, kFrameTime, zero), "pelvis");
  const BvhClip one_frame = parse_bvh(rig_text(rig21(), 1, kFrameTime, zero));
  EXPECT_THROW(bvh_motion(one_frame), Error);
  BvhMotionOptions bad;
  bad.smoothing_s = -1;
  EXPECT_THROW(bvh_motion(parse_bvh(rig_text(rig21(), 3, kFrameTime, zero)), bad), Error);
}
