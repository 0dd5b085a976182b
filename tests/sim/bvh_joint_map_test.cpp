// BVH joint maps (bvh_joint_map.hpp): the built-in maps against the name table, a rig with its
// own names driven through a joint-map file, and the errors naming the file's line.
#include "sim/bvh_joint_map.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "common/error.hpp"
#include "sim/bvh_motion.hpp"
#include "sim/bvh_retarget.hpp"
#include "test_rigs.hpp"

using posefuse::Error;
using posefuse::ErrorCode;
using namespace posefuse::sim;
using posefuse::sim::testing::rig21;
using posefuse::sim::testing::rig_cmu31;
using posefuse::sim::testing::rig_text;
using posefuse::sim::testing::RigJointSpec;
namespace body = posefuse::body;

namespace {

constexpr double kFrameTime = 1.0 / 60;

// A smooth motion of every joint (root moving too), the same values whatever the joint names.
double wave(int f, int j, int c) {
  const double t = f * kFrameTime;
  if (j == 0 && c < 3) return (c == 1 ? 95.0 : 0.0) + 5.0 * std::sin(1.3 * t + c);
  return 20.0 * std::sin(0.7 * t + 0.37 * j + 1.1 * c);
}

// rig21 with names no built-in table knows (game-engine style).
std::vector<RigJointSpec> renamed_rig() {
  std::vector<RigJointSpec> rig = rig21();
  const std::vector<std::string> names = {
      "torso_base", "thigh_l",    "calf_l",   "foot_l",     "ball_l",     "thigh_r",    "calf_r",
      "foot_r",     "ball_r",     "spine_01", "spine_02",   "neck_01",    "skull",      "clavicle_l",
      "upperarm_l", "lowerarm_l", "hand_l",   "clavicle_r", "upperarm_r", "lowerarm_r", "hand_r"};
  for (std::size_t j = 0; j < rig.size(); ++j) rig[j].name = names[j];
  return rig;
}

const char* const kRenamedMap = R"(# the renamed rig, joint by joint
pelvis = torso_base
left_hip = thigh_l
right_hip = thigh_r
left_knee = calf_l
right_knee = calf_r
left_ankle = foot_l
right_ankle = foot_r
left_foot = ball_l
right_foot = ball_r
spine1 = spine_01
spine2 = spine_02
neck = neck_01
head = skull
left_collar = clavicle_l
right_collar = clavicle_r
left_shoulder = upperarm_l
right_shoulder = upperarm_r
left_elbow = lowerarm_l
right_elbow = lowerarm_r
left_wrist = hand_l   # trailing comments are fine
right_wrist = hand_r
)";

// The text with line `line` (1-based) replaced.
std::string with_line(const std::string& text, int line, const std::string& replacement) {
  std::string out;
  int n = 0;
  std::size_t begin = 0;
  while (begin < text.size()) {
    const std::size_t end = std::min(text.find('\n', begin), text.size());
    ++n;
    out += (n == line ? replacement : text.substr(begin, end - begin)) + "\n";
    begin = end + 1;
  }
  return out;
}

void expect_error(const std::function<void()>& f, const std::string& field, const std::string& needle) {
  try {
    f();
    ADD_FAILURE() << "no error; expected " << field << ": ..." << needle;
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_EQ(e.field(), field) << e.what();
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

}  // namespace

TEST(BvhJointMap, BuiltInMapsPickWhatTheNameTablePicksOnTheirRigs) {
  const BvhClip a = parse_bvh(rig_text(rig21(), 2, kFrameTime, wave));
  const BvhClip b = parse_bvh(rig_text(rig_cmu31(), 2, kFrameTime, wave));
  const BvhJointMatch auto21 = match_bvh_joint_map(auto_bvh_joint_map(), a.skeleton);
  const BvhJointMatch map21 = match_bvh_joint_map(bvh_joint_map_named("mocap21"), a.skeleton);
  const BvhJointMatch auto31 = match_bvh_joint_map(auto_bvh_joint_map(), b.skeleton);
  const BvhJointMatch map31 = match_bvh_joint_map(bvh_joint_map_named("cmu31"), b.skeleton);
  EXPECT_EQ(map21.bvh_joint, auto21.bvh_joint);
  EXPECT_EQ(map31.bvh_joint, auto31.bvh_joint);
  EXPECT_EQ(map21.bvh_joint[body::kSpine3], -1);
  EXPECT_EQ(b.skeleton.joints[static_cast<std::size_t>(map31.bvh_joint[body::kSpine1])].name, "LowerBack");
  EXPECT_EQ(map21.line[body::kPelvis], 2);  // line 1 is the comment
  // Each built-in map is for its rig: CMU's map on the 21-joint rig names the missing joint.
  expect_error([&] { match_bvh_joint_map(bvh_joint_map_named("cmu31"), a.skeleton); }, "cmu31:11",
               "'LowerBack' (SMPL joint 'spine1') is not a joint of the BVH clip");
  try {
    bvh_joint_map_named("cmu32");  // neither built in nor a file
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kNotFound);
    EXPECT_EQ(e.field(), "cmu32");
  }
}

TEST(BvhJointMap, ARigWithItsOwnNamesMovesLikeTheOriginalThroughAMapFile) {
  const BvhClip original = parse_bvh(rig_text(rig21(), 40, kFrameTime, wave));
  const BvhClip renamed = parse_bvh(rig_text(renamed_rig(), 40, kFrameTime, wave));
  expect_error([&] { bvh_motion(renamed); }, "bvh.joints", "SMPL joint 'pelvis'");  // the name table fails
  BvhMotionOptions options;
  options.joint_map = parse_bvh_joint_map(kRenamedMap, "renamed.map");
  const BodyMotion moved = bvh_motion(renamed, options);
  const BodyMotion reference = bvh_motion(original);
  ASSERT_DOUBLE_EQ(moved.duration_s, reference.duration_s);
  for (double t = 0; t <= moved.duration_s; t += 0.05) {
    EXPECT_LT((moved.poses(t) - reference.poses(t)).cwiseAbs().maxCoeff(), 1e-12) << t;
  }
}

TEST(BvhJointMap, BadFilesAreRefusedNamingTheLine) {
  const std::string text = kRenamedMap;
  EXPECT_EQ(parse_bvh_joint_map(text, "m").entries.size(), 21u);
  expect_error([&] { parse_bvh_joint_map(with_line(text, 3, "left_hip thigh_l"), "m"); }, "m:3",
               "expected 'smpl_joint = BvhJointName'");
  expect_error([&] { parse_bvh_joint_map(with_line(text, 3, "left_hip = thigh l"), "m"); }, "m:3",
               "one name each side");
  expect_error([&] { parse_bvh_joint_map(with_line(text, 3, "left_hip ="), "m"); }, "m:3", "one name each side");
  expect_error([&] { parse_bvh_joint_map(with_line(text, 3, "left_thigh = thigh_l"), "m"); }, "m:3",
               "'left_thigh' is not an SMPL joint (known: pelvis, left_hip");
  expect_error([&] { parse_bvh_joint_map(with_line(text, 3, "left_hand = thigh_l"), "m"); }, "m:3",
               "follow the wrists");
  expect_error([&] { parse_bvh_joint_map(with_line(text, 4, "left_hip = thigh_r"), "m"); }, "m:4",
               "'left_hip' is mapped twice (first on line 3)");
  expect_error([&] { parse_bvh_joint_map(with_line(text, 4, "right_hip = THIGH_L"), "m"); }, "m:4",
               "BVH joint 'THIGH_L' already drives 'left_hip' (line 3)");
  expect_error([&] { parse_bvh_joint_map(with_line(text, 21, "# no left wrist"), "m"); }, "m",
               "no line for the required SMPL joint 'left_wrist'");
  // Optional joints may be left out.
  EXPECT_NO_THROW(parse_bvh_joint_map(with_line(with_line(text, 15, ""), 11, ""), "m"));

  // Against a clip: a name the rig lacks, and a mapping that contradicts the hierarchy.
  const BvhClip renamed = parse_bvh(rig_text(renamed_rig(), 3, kFrameTime, wave));
  BvhMotionOptions options;
  options.joint_map = parse_bvh_joint_map(with_line(text, 19, "left_elbow = forearm_l"), "m");
  expect_error([&] { bvh_motion(renamed, options); }, "m:19", "'forearm_l' (SMPL joint 'left_elbow') is not a joint");
  options.joint_map =
      parse_bvh_joint_map(with_line(with_line(text, 19, "left_elbow = hand_l"), 21, "left_wrist = lowerarm_l"), "m");
  expect_error([&] { bvh_motion(renamed, options); }, "m:21",
               "'lowerarm_l' (SMPL joint 'left_wrist') is not below 'hand_l'");
}
