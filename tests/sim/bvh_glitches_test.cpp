// Mocap glitches (bvh_glitches.hpp) on clips made here: a smooth 60 fps motion of the 21-joint
// rig with one glitch put in by hand, found by its frame range and joint and repaired.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "common/error.hpp"
#include "sim/bvh.hpp"
#include "sim/bvh_glitches.hpp"
#include "test_rigs.hpp"

using namespace posefuse;
using namespace posefuse::sim;
using std::numbers::pi;

namespace rigs = posefuse::sim::testing;

namespace {

constexpr int kFrames = 120;
constexpr double kFrameTime = 1.0 / 60;

// Channel c (Z, Y, X rotation in degrees; root: X, Y, Z position first) of a smooth motion:
// the right arm raised and swinging, the left arm lowered and swinging, the right forearm
// rolling fast (15 rad/s about its bone: 14.3 degrees per frame) and bending.
double smooth_value(const std::vector<rigs::RigJointSpec>& rig, int frame, int joint, int c) {
  const double t = frame * kFrameTime;
  const std::string& name = rig[static_cast<std::size_t>(joint)].name;
  if (rig[static_cast<std::size_t>(joint)].root) return c == 1 ? 95.0 : 0.0;
  if (name == "RightArm" && c == 0) return -60.0 + 20.0 * std::sin(2 * pi * 0.7 * t);
  if (name == "LeftArm" && c == 0) return -50.0 + 15.0 * std::sin(2 * pi * 0.5 * t);
  if (name == "LeftArm" && c == 1) return 20.0 * std::sin(2 * pi * 0.4 * t);
  if (name == "RightForeArm" && c == 1) return 40.0 + 30.0 * std::sin(2 * pi * 0.6 * t);
  if (name == "RightForeArm" && c == 2) return 15.0 * t * 180.0 / pi;
  return 0.0;
}

BvhClip smooth_clip(const std::vector<rigs::RigJointSpec>& rig, const rigs::RigValue& value) {
  return parse_bvh(rigs::rig_text(rig, kFrames, kFrameTime, value), "made.bvh");
}

BvhClip smooth_clip(const std::vector<rigs::RigJointSpec>& rig) {
  return smooth_clip(rig, [&](int f, int j, int c) { return smooth_value(rig, f, j, c); });
}

// The angle between two rotations from the vector part (accurate near zero, where
// angle_between's acos is not: it reads 3e-8 rad for equal rotations).
double angle(const Quat& a, const Quat& b) {
  const Quat d = a.conjugate() * b;
  return 2.0 * std::atan2(d.vec().norm(), std::abs(d.w()));
}

double worst_rotation_difference(const BvhClip& a, const BvhClip& b) {
  double worst = 0;
  for (std::size_t f = 0; f < a.frames.size(); ++f) {
    for (std::size_t j = 0; j < a.skeleton.joints.size(); ++j) {
      worst = std::max(worst, angle(a.frames[f].parent_from_joint[j], b.frames[f].parent_from_joint[j]));
    }
  }
  return worst;
}

// The 180 degree flip about the forearm bone (x in the 21-joint rig) of frames a..b.
void flip_forearm(BvhClip& clip, int a, int b) {
  const int j = clip.skeleton.find("RightForeArm");
  for (int f = a; f <= b; ++f) {
    Quat& q = clip.frames[static_cast<std::size_t>(f)].parent_from_joint[static_cast<std::size_t>(j)];
    q = (q * Quat(Eigen::AngleAxisd(pi, Vec3::UnitX()))).normalized();
  }
}

// Frames 30..44 labelled the other way round (rigs::with_arms_swapped).
BvhClip swapped_arms_clip(const std::vector<rigs::RigJointSpec>& rig) {
  return smooth_clip(rig, rigs::with_arms_swapped(
                              rig, [&](int f, int j, int c) { return smooth_value(rig, f, j, c); }, 30, 44));
}

}  // namespace

TEST(BvhGlitches, SmoothFastMotionHasNone) {
  const BvhClip clip = smooth_clip(rigs::rig21());
  const BvhRepair repair = repair_bvh_glitches(clip);
  EXPECT_TRUE(repair.glitches.empty()) << describe(repair.glitches.front(), kFrameTime);
  EXPECT_EQ(worst_rotation_difference(repair.clip, clip), 0.0);
}

TEST(BvhGlitches, FlippedFramesAreNamedAndInterpolated) {
  const BvhClip clean = smooth_clip(rigs::rig21());
  BvhClip glitched = clean;
  flip_forearm(glitched, 50, 51);
  const BvhRepair repair = repair_bvh_glitches(glitched);
  ASSERT_EQ(repair.glitches.size(), 1u);
  const BvhGlitch& g = repair.glitches[0];
  EXPECT_EQ(g.kind, BvhGlitchKind::kFlip);
  EXPECT_EQ(g.first_frame, 50);
  EXPECT_EQ(g.last_frame, 51);
  EXPECT_EQ(g.joint, "RightForeArm");
  const std::string line = describe(g, kFrameTime);
  std::printf("%s\n", line.c_str());
  EXPECT_NE(line.find("bvh frames 50..51 (0.833..0.850 s), RightForeArm"), std::string::npos) << line;
  // Slerp across H = 3 frame steps is off the motion by at most H^2 / 8 times its angular
  // acceleration: bend b = 30 deg sin(2 pi 0.6 t) under the 15 rad/s roll r gives at most
  // |r'| |b'| + |b''| = 15 * 1.97 + 7.44 = 37.1 rad/s^2, so (0.05 s)^2 / 8 * 37.1 = 0.0116 rad.
  const double worst = worst_rotation_difference(repair.clip, clean);
  std::printf("repaired frames off the clean motion by %.5f rad\n", worst);
  EXPECT_LT(worst, 0.0116);
}

TEST(BvhGlitches, FlippedFirstAndLastFramesAreHeld) {
  const BvhClip clean = smooth_clip(rigs::rig21());
  BvhClip glitched = clean;
  flip_forearm(glitched, 0, 0);
  flip_forearm(glitched, kFrames - 2, kFrames - 1);
  const BvhRepair repair = repair_bvh_glitches(glitched);
  ASSERT_EQ(repair.glitches.size(), 2u);
  EXPECT_EQ(repair.glitches[0].first_frame, 0);
  EXPECT_EQ(repair.glitches[0].last_frame, 0);
  EXPECT_EQ(repair.glitches[1].first_frame, kFrames - 2);
  EXPECT_EQ(repair.glitches[1].last_frame, kFrames - 1);
  for (const BvhGlitch& g : repair.glitches) std::printf("%s\n", describe(g, kFrameTime).c_str());
  // Held at the neighbouring good frame: off the motion by at most two frame steps of the
  // forearm (15 rad/s roll and a bend of at most 1.97 rad/s): 2 / 60 s * 17 rad/s = 0.57 rad.
  EXPECT_LT(worst_rotation_difference(repair.clip, clean), 2.0 / 60 * 17.0);
}

TEST(BvhGlitches, SwappedArmsAreNamedAndSwappedBack) {
  const auto rig = rigs::symmetric_rig21();
  const BvhClip clean = smooth_clip(rig);
  const BvhClip swapped = swapped_arms_clip(rig);
  const BvhRepair repair = repair_bvh_glitches(swapped);
  ASSERT_EQ(repair.glitches.size(), 1u) << describe(repair.glitches.back(), kFrameTime);
  const BvhGlitch& g = repair.glitches[0];
  EXPECT_EQ(g.kind, BvhGlitchKind::kArmSwap);
  EXPECT_EQ(g.first_frame, 30);
  EXPECT_EQ(g.last_frame, 44);
  EXPECT_EQ(g.joint, "LeftShoulder/RightShoulder");
  std::printf("%s\n", describe(g, kFrameTime).c_str());
  // Swapped back exactly (up to the file's 12 digits).
  EXPECT_LT(worst_rotation_difference(repair.clip, clean), 1e-9);
}

TEST(BvhGlitches, BoneLengthJumpIsNamedAndInterpolated) {
  const BvhClip clean = smooth_clip(rigs::rig21());
  BvhClip glitched = clean;
  const auto j = static_cast<std::size_t>(glitched.skeleton.find("LeftForeArm"));
  for (int f = 70; f <= 72; ++f) glitched.frames[static_cast<std::size_t>(f)].translation[j] = Vec3(8.0, 0, 0);
  const BvhRepair repair = repair_bvh_glitches(glitched);
  ASSERT_EQ(repair.glitches.size(), 1u);
  const BvhGlitch& g = repair.glitches[0];
  EXPECT_EQ(g.kind, BvhGlitchKind::kBoneLength);
  EXPECT_EQ(g.first_frame, 70);
  EXPECT_EQ(g.last_frame, 72);
  EXPECT_EQ(g.joint, "LeftForeArm");
  std::printf("%s\n", describe(g, kFrameTime).c_str());
  for (const BvhLocalPose& pose : repair.clip.frames) EXPECT_EQ(pose.translation[j], Vec3::Zero());
}

TEST(BvhGlitches, FlipThatStaysIsRefusedWithItsFrames) {
  BvhClip glitched = smooth_clip(rigs::rig21());
  flip_forearm(glitched, 50, 89);  // 40 frames: more than max_glitch_frames
  try {
    repair_bvh_glitches(glitched);
    FAIL() << "a 40-frame flip was repaired";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_EQ(e.field(), "bvh.frames[50..61]");
    EXPECT_NE(std::string(e.what()).find("RightForeArm"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("does not come back"), std::string::npos) << e.what();
  }
  // With a longer allowance the same 40 frames are interpolated.
  BvhGlitchOptions longer;
  longer.max_glitch_frames = 40;
  const BvhRepair repair = repair_bvh_glitches(glitched, longer);
  ASSERT_EQ(repair.glitches.size(), 1u);
  EXPECT_EQ(repair.glitches[0].first_frame, 50);
  EXPECT_EQ(repair.glitches[0].last_frame, 89);
}

TEST(BvhGlitches, BoneLengthRunTooLongIsRefused) {
  BvhClip glitched = smooth_clip(rigs::rig21());
  const auto j = static_cast<std::size_t>(glitched.skeleton.find("LeftForeArm"));
  for (int f = 20; f <= 39; ++f) glitched.frames[static_cast<std::size_t>(f)].translation[j] = Vec3(8.0, 0, 0);
  try {
    repair_bvh_glitches(glitched);
    FAIL() << "a 20-frame bone-length jump was repaired";
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "bvh.frames[20..39]");
    EXPECT_NE(std::string(e.what()).find("LeftForeArm"), std::string::npos) << e.what();
  }
}

TEST(BvhGlitches, RejectsBadOptions) {
  const BvhClip clip = smooth_clip(rigs::rig21());
  BvhGlitchOptions o;
  o.max_joint_rate_rad_s = 0;
  EXPECT_THROW(repair_bvh_glitches(clip, o), Error);
  o = {};
  o.max_glitch_frames = 0;
  EXPECT_THROW(repair_bvh_glitches(clip, o), Error);
  o = {};
  o.arm_swap_ratio = 1.0;
  EXPECT_THROW(repair_bvh_glitches(clip, o), Error);
}

TEST(BvhGlitches, ArmSwapsAreLookedForOnTheJointMapsArms) {
  // The swapped clip with every joint renamed: the name table finds no arms, so the swap looks
  // like an arm turning too fast and never coming back (refused); a joint map naming the arms
  // finds the swap as on the original names.
  BvhClip swapped = swapped_arms_clip(rigs::symmetric_rig21());
  std::string map_text;
  const auto& names = posefuse::body::smpl_joint_names();
  const BvhJointMatch original = match_bvh_joint_map(auto_bvh_joint_map(), swapped.skeleton);
  for (BvhJoint& joint : swapped.skeleton.joints) joint.name = "j_" + joint.name;
  for (int j = 0; j < posefuse::body::kNumJoints; ++j) {
    const int b = original.bvh_joint[static_cast<std::size_t>(j)];
    if (b >= 0)
      map_text += std::string(names[static_cast<std::size_t>(j)]) + " = " +
                  swapped.skeleton.joints[static_cast<std::size_t>(b)].name + "\n";
  }
  EXPECT_THROW(repair_bvh_glitches(swapped), Error);
  const BvhRepair repair = repair_bvh_glitches(swapped, {}, parse_bvh_joint_map(map_text, "renamed.map"));
  ASSERT_EQ(repair.glitches.size(), 1u);
  EXPECT_EQ(repair.glitches[0].kind, BvhGlitchKind::kArmSwap);
  EXPECT_EQ(repair.glitches[0].first_frame, 30);
  EXPECT_EQ(repair.glitches[0].last_frame, 44);
  EXPECT_EQ(repair.glitches[0].joint, "j_LeftShoulder/j_RightShoulder");
}
