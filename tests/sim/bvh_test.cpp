#include "sim/bvh.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <sstream>

#include "common/error.hpp"

using posefuse::Error;
using posefuse::ErrorCode;
using namespace posefuse::sim;

namespace {

using std::numbers::pi;

// Root with 6 channels, Mid and Tip with 3 each, an End Site on Tip. Lengths in cm.
std::string chain_text(const std::string& mid_channels, const std::vector<std::string>& frames) {
  std::ostringstream s;
  s << "HIERARCHY\n"
       "ROOT Root\n"
       "{\n"
       "  OFFSET 0 0 0\n"
       "  CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n"
       "  JOINT Mid\n"
       "  {\n"
       "    OFFSET 0 10 0\n"
       "    CHANNELS 3 "
    << mid_channels
    << "\n"
       "    JOINT Tip\n"
       "    {\n"
       "      OFFSET 0 20 0\n"
       "      CHANNELS 3 Zrotation Yrotation Xrotation\n"
       "      End Site\n"
       "      {\n"
       "        OFFSET 0 5 0\n"
       "      }\n"
       "    }\n"
       "  }\n"
       "}\n"
       "MOTION\n"
       "Frames: "
    << frames.size()
    << "\n"
       "Frame Time: 0.5\n";
  for (const auto& f : frames) s << f << "\n";
  return s.str();
}

// The line numbers of chain_text: MOTION is line 21, the first frame line 24.
constexpr int kFirstFrameLine = 24;

void expect_near(const Vec3& a, const Vec3& b, double tol = 1e-12) {
  EXPECT_NEAR((a - b).norm(), 0.0, tol) << "got " << a.transpose() << " want " << b.transpose();
}

// Expects parse_bvh(text) to throw with the given code and a field naming `line`.
void expect_rejected(const std::string& text, int line, ErrorCode code) {
  try {
    parse_bvh(text, "clip.bvh");
    FAIL() << "expected an error at line " << line;
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "clip.bvh:" + std::to_string(line)) << e.what();
    EXPECT_EQ(e.code(), code) << e.what();
  }
}

}  // namespace

TEST(Bvh, ParsesChainStructure) {
  const BvhClip clip = parse_bvh(chain_text("Zrotation Yrotation Xrotation", {"0 0 0 0 0 0 0 0 0 0 0 0"}));
  ASSERT_EQ(clip.skeleton.joints.size(), 3u);
  EXPECT_EQ(clip.skeleton.channel_count, 12);
  EXPECT_EQ(clip.skeleton.joints[1].name, "Mid");
  EXPECT_EQ(clip.skeleton.joints[1].parent, 0);
  EXPECT_EQ(clip.skeleton.joints[2].parent, 1);
  EXPECT_EQ(clip.skeleton.joints[2].first_channel, 9);
  EXPECT_FALSE(clip.skeleton.joints[1].end_site_offset.has_value());
  ASSERT_TRUE(clip.skeleton.joints[2].end_site_offset.has_value());
  EXPECT_EQ(clip.frame_count(), 1);
  EXPECT_DOUBLE_EQ(clip.frame_time_s, 0.5);
  EXPECT_EQ(clip.skeleton.find("Tip"), 2);
  EXPECT_EQ(clip.skeleton.find("Nope"), -1);
}

// Hand computation in the file frame M (cm), then W = (x, -z, y) * 0.01.
TEST(Bvh, ForwardKinematicsMatchesHandComputation) {
  const BvhClip clip = parse_bvh(
      chain_text("Zrotation Yrotation Xrotation", {"1 2 3 0 0 0 0 0 0 0 0 0", "100 0 0 90 0 0 0 0 90 0 0 0"}));
  auto to_W = [](double x, double y, double z) { return Vec3(0.01 * x, -0.01 * z, 0.01 * y); };

  const BvhWorldPose rest = forward_kinematics(clip.skeleton, clip.frames[0], 0.01);
  expect_near(rest.p_W_m[0], to_W(1, 2, 3));
  expect_near(rest.p_W_m[1], to_W(1, 12, 3));
  expect_near(rest.p_W_m[2], to_W(1, 32, 3));
  expect_near(*rest.end_site_p_W_m[2], to_W(1, 37, 3));
  EXPECT_FALSE(rest.end_site_p_W_m[1].has_value());

  // Root: Rz(90) maps M's y to -x. Mid: Rx(90) maps y to z; Rz(90) keeps z.
  const BvhWorldPose bent = forward_kinematics(clip.skeleton, clip.frames[1], 0.01);
  expect_near(bent.p_W_m[0], to_W(100, 0, 0));
  expect_near(bent.p_W_m[1], to_W(90, 0, 0));
  expect_near(bent.p_W_m[2], to_W(90, 0, 20));
  expect_near(*bent.end_site_p_W_m[2], to_W(90, 0, 25));
  // The Tip's world rotation is W_from_M * Rz(90) * Rx(90).
  const Quat expected = W_from_bvh_world() * Quat(Eigen::AngleAxisd(pi / 2, Vec3::UnitZ())) *
                        Quat(Eigen::AngleAxisd(pi / 2, Vec3::UnitX()));
  EXPECT_LT(posefuse::geometry::angle_between(bent.W_from_joint[2], expected), 1e-12);
}

TEST(Bvh, WorldFrameIsZUp) {
  // M's +y (up) must become W's +z, M's +z becomes W's -y.
  expect_near(W_from_bvh_world() * Vec3::UnitY(), Vec3::UnitZ(), 1e-15);
  expect_near(W_from_bvh_world() * Vec3::UnitZ(), -Vec3::UnitY(), 1e-15);
  expect_near(W_from_bvh_world() * Vec3::UnitX(), Vec3::UnitX(), 1e-15);
}

// The same values under two declared orders give Rz*Ry*Rx and Rx*Ry*Rz respectively.
TEST(Bvh, ChannelOrderAsDeclared) {
  // Mid: Z = 90, X = 90 (written in the declared order).
  const BvhClip zyx = parse_bvh(chain_text("Zrotation Yrotation Xrotation", {"0 0 0 0 0 0 90 0 90 0 0 0"}));
  const BvhClip xyz = parse_bvh(chain_text("Xrotation Yrotation Zrotation", {"0 0 0 0 0 0 90 0 90 0 0 0"}));
  auto to_W = [](double x, double y, double z) { return Vec3(0.01 * x, -0.01 * z, 0.01 * y); };
  // Rz*Rx (0,20,0): Rx takes it to (0,0,20), Rz keeps it.
  expect_near(forward_kinematics(zyx.skeleton, zyx.frames[0], 0.01).p_W_m[2], to_W(0, 10, 20));
  // Rx*Rz (0,20,0): Rz takes it to (-20,0,0), Rx keeps it.
  expect_near(forward_kinematics(xyz.skeleton, xyz.frames[0], 0.01).p_W_m[2], to_W(-20, 10, 0));
  // A root that declares its rotations before its positions.
  const std::string text =
      "HIERARCHY\nROOT R\n{\n OFFSET 1 0 0\n CHANNELS 6 Yrotation Xposition Zposition Yposition\n"
      "  Xrotation Zrotation\n End Site\n {\n  OFFSET 0 0 10\n }\n}\nMOTION\nFrames: 1\n"
      "Frame Time: 0.01\n90 5 7 6 0 0\n";
  const BvhClip clip = parse_bvh(text);
  const BvhWorldPose pose = forward_kinematics(clip.skeleton, clip.frames[0], 1.0);
  expect_near(pose.p_W_m[0], to_W(6, 6, 7) * 100.0);
  // Ry(90) maps z to x.
  expect_near(*pose.end_site_p_W_m[0], to_W(16, 6, 7) * 100.0);
}

namespace {

// A rig with the structure of CMU's 31-joint BVH export: joint names, End Sites on toes, head,
// fingers and thumbs, a zero-channel joint, and joint-specific channel orders.
struct RigJoint {
  const char* name;
  int parent;
  const char* channels;
  bool end_site;
};

const RigJoint kCmuLikeRig[] = {
    {"Hips", -1, "6 Xposition Yposition Zposition Zrotation Yrotation Xrotation", false},
    {"LHipJoint", 0, "0", false},
    {"LeftUpLeg", 1, "3 Zrotation Yrotation Xrotation", false},
    {"LeftLeg", 2, "3 Zrotation Yrotation Xrotation", false},
    {"LeftFoot", 3, "3 Zrotation Yrotation Xrotation", false},
    {"LeftToeBase", 4, "3 Zrotation Yrotation Xrotation", true},
    {"RHipJoint", 0, "3 Zrotation Yrotation Xrotation", false},
    {"RightUpLeg", 6, "3 Zrotation Yrotation Xrotation", false},
    {"RightLeg", 7, "3 Zrotation Yrotation Xrotation", false},
    {"RightFoot", 8, "3 Zrotation Yrotation Xrotation", false},
    {"RightToeBase", 9, "3 Zrotation Yrotation Xrotation", true},
    {"LowerBack", 0, "3 Zrotation Yrotation Xrotation", false},
    {"Spine", 11, "3 Zrotation Yrotation Xrotation", false},
    {"Spine1", 12, "3 Zrotation Yrotation Xrotation", false},
    {"Neck", 13, "3 Zrotation Yrotation Xrotation", false},
    {"Neck1", 14, "3 Zrotation Yrotation Xrotation", false},
    {"Head", 15, "3 Zrotation Yrotation Xrotation", true},
    {"LeftShoulder", 13, "3 Zrotation Xrotation Yrotation", false},
    {"LeftArm", 17, "3 Zrotation Xrotation Yrotation", false},
    {"LeftForeArm", 18, "3 Zrotation Xrotation Yrotation", false},
    {"LeftHand", 19, "3 Zrotation Xrotation Yrotation", false},
    {"LeftFingerBase", 20, "3 Zrotation Xrotation Yrotation", false},
    {"LeftHandIndex1", 21, "3 Zrotation Xrotation Yrotation", true},
    {"LThumb", 20, "3 Zrotation Xrotation Yrotation", true},
    {"RightShoulder", 13, "3 Yrotation Xrotation Zrotation", false},
    {"RightArm", 24, "3 Yrotation Xrotation Zrotation", false},
    {"RightForeArm", 25, "3 Yrotation Xrotation Zrotation", false},
    {"RightHand", 26, "3 Yrotation Xrotation Zrotation", false},
    {"RightFingerBase", 27, "3 Yrotation Xrotation Zrotation", false},
    {"RightHandIndex1", 28, "3 Yrotation Xrotation Zrotation", true},
    {"RThumb", 27, "3 Yrotation Xrotation Zrotation", true},
};
constexpr int kRigJoints = 31;

Vec3 rig_offset(int j) { return Vec3(0.5 * j - 3.0, 2.0 + 0.3 * j, std::sin(j) * 4.0); }

std::string cmu_like_text(int frames, std::vector<std::vector<double>>& values) {
  std::ostringstream s;
  s.precision(17);  // the test compares decoded values with the doubles written
  int channels = 0;
  std::function<void(int, int)> write = [&](int j, int depth) {
    const std::string pad(2 * static_cast<std::size_t>(depth), ' ');
    s << pad << (j == 0 ? "ROOT " : "JOINT ") << kCmuLikeRig[j].name << "\n" << pad << "{\n";
    const Vec3 o = rig_offset(j);
    s << pad << "  OFFSET " << o.x() << " " << o.y() << " " << o.z() << "\n";
    s << pad << "  CHANNELS " << kCmuLikeRig[j].channels << "\n";
    channels += kCmuLikeRig[j].channels[0] - '0';
    for (int c = 0; c < kRigJoints; ++c) {
      if (kCmuLikeRig[c].parent == j) write(c, depth + 1);
    }
    if (kCmuLikeRig[j].end_site) {
      s << pad << "  End Site\n" << pad << "  {\n" << pad << "    OFFSET 0 3 1\n" << pad << "  }\n";
    }
    s << pad << "}\n";
  };
  s << "HIERARCHY\n";
  write(0, 0);
  s << "MOTION\nFrames: " << frames << "\nFrame Time: 0.00833333\n";
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-180.0, 180.0);
  values.assign(static_cast<std::size_t>(frames), std::vector<double>(static_cast<std::size_t>(channels)));
  for (auto& frame : values) {
    for (double& v : frame) v = angle(rng);
    for (std::size_t k = 0; k < frame.size(); ++k) s << (k ? " " : "") << frame[k];
    s << "\n";
  }
  return s.str();
}

}  // namespace

TEST(Bvh, CmuLike31JointRig) {
  std::vector<std::vector<double>> values;
  const BvhClip clip = parse_bvh(cmu_like_text(4, values));
  ASSERT_EQ(clip.skeleton.joints.size(), static_cast<std::size_t>(kRigJoints));
  EXPECT_EQ(clip.skeleton.channel_count, 6 + 29 * 3);
  EXPECT_EQ(clip.frame_count(), 4);
  int end_sites = 0;
  for (const BvhJoint& joint : clip.skeleton.joints) end_sites += joint.end_site_offset ? 1 : 0;
  EXPECT_EQ(end_sites, 7);
  // File order is depth-first; parents are found by name.
  for (int j = 0; j < kRigJoints; ++j) {
    const int index = clip.skeleton.find(kCmuLikeRig[j].name);
    ASSERT_GE(index, 0) << kCmuLikeRig[j].name;
    const int parent = clip.skeleton.joints[static_cast<std::size_t>(index)].parent;
    if (kCmuLikeRig[j].parent < 0) {
      EXPECT_EQ(parent, -1);
    } else {
      EXPECT_EQ(clip.skeleton.joints[static_cast<std::size_t>(parent)].name, kCmuLikeRig[kCmuLikeRig[j].parent].name);
    }
  }
  // LeftArm is "Zrotation Xrotation Yrotation": its local rotation is Rz * Rx * Ry.
  const int left_arm = clip.skeleton.find("LeftArm");
  const BvhJoint& joint = clip.skeleton.joints[static_cast<std::size_t>(left_arm)];
  const auto& v = values[2];
  auto rad = [&](int k) { return v[static_cast<std::size_t>(joint.first_channel + k)] * pi / 180.0; };
  const Quat expected = Quat(Eigen::AngleAxisd(rad(0), Vec3::UnitZ())) *
                        Quat(Eigen::AngleAxisd(rad(1), Vec3::UnitX())) * Quat(Eigen::AngleAxisd(rad(2), Vec3::UnitY()));
  EXPECT_LT(
      posefuse::geometry::angle_between(clip.frames[2].parent_from_joint[static_cast<std::size_t>(left_arm)], expected),
      1e-9);

  // Bones keep their lengths under any pose; end sites sit at their offset's length.
  for (const BvhLocalPose& frame : clip.frames) {
    const BvhWorldPose pose = forward_kinematics(clip.skeleton, frame, 0.01);
    for (std::size_t j = 1; j < clip.skeleton.joints.size(); ++j) {
      const BvhJoint& b = clip.skeleton.joints[j];
      const double length = (pose.p_W_m[j] - pose.p_W_m[static_cast<std::size_t>(b.parent)]).norm();
      EXPECT_NEAR(length, 0.01 * b.offset.norm(), 1e-12) << b.name;
      if (b.end_site_offset) {
        EXPECT_NEAR((*pose.end_site_p_W_m[j] - pose.p_W_m[j]).norm(), 0.01 * b.end_site_offset->norm(), 1e-12);
      }
    }
  }
}

TEST(Bvh, ToleratesCrlfAndBlankLines) {
  std::string text =
      chain_text("Zrotation Yrotation Xrotation", {"1 2 3 0 0 0 0 0 0 0 0 0", "", "1 2 3 0 0 0 0 0 0 0 0 0"});
  // chain_text counts the blank line as a frame; fix the count and use CRLF endings.
  text.replace(text.find("Frames: 3"), 9, "Frames: 2");
  std::string crlf;
  for (char c : text) {
    if (c == '\n') crlf += '\r';
    crlf += c;
  }
  EXPECT_EQ(parse_bvh(crlf).frame_count(), 2);
}

TEST(Bvh, ResampleSlerpsRotationsAndInterpolatesPositions) {
  // Two frames 0.5 s apart: root x 0 -> 100, Mid's Z rotation 0 -> 90 degrees.
  const BvhClip clip =
      parse_bvh(chain_text("Zrotation Yrotation Xrotation", {"0 0 0 0 0 0 0 0 0 0 0 0", "100 0 0 0 0 0 90 0 0 0 0 0"}));
  const BvhClip up = resample(clip, 8.0);  // 0, 0.125, ..., 0.5 s
  ASSERT_EQ(up.frame_count(), 5);
  EXPECT_DOUBLE_EQ(up.frame_time_s, 0.125);
  for (int k = 0; k < 5; ++k) {
    const double u = k / 4.0;
    const BvhLocalPose& f = up.frames[static_cast<std::size_t>(k)];
    EXPECT_NEAR(f.translation[0].x(), 100.0 * u, 1e-9);
    const Quat expected(Eigen::AngleAxisd(u * pi / 2, Vec3::UnitZ()));
    EXPECT_LT(posefuse::geometry::angle_between(f.parent_from_joint[1], expected), 1e-12);
  }
  // Downsampling keeps frames within the duration only.
  EXPECT_EQ(resample(clip, 3.0).frame_count(), 2);  // 0 and 1/3 s
  EXPECT_THROW(resample(clip, 0.0), Error);
  EXPECT_THROW(resample(clip, -5.0), Error);
}

TEST(Bvh, ResampleTakesShortestArc) {
  // 170 -> -170 degrees about z: the short way is through 180, not through 0.
  const BvhClip clip = parse_bvh(
      chain_text("Zrotation Yrotation Xrotation", {"0 0 0 0 0 0 170 0 0 0 0 0", "0 0 0 0 0 0 -170 0 0 0 0 0"}));
  const BvhClip mid = resample(clip, 4.0);  // 0, 0.25, 0.5 s
  ASSERT_EQ(mid.frame_count(), 3);
  const Quat half_turn(Eigen::AngleAxisd(pi, Vec3::UnitZ()));
  EXPECT_LT(posefuse::geometry::angle_between(mid.frames[1].parent_from_joint[1], half_turn), 1e-12);
}

TEST(Bvh, ForwardKinematicsRejectsBadInput) {
  const BvhClip clip = parse_bvh(chain_text("Zrotation Yrotation Xrotation", {"0 0 0 0 0 0 0 0 0 0 0 0"}));
  EXPECT_THROW(forward_kinematics(clip.skeleton, clip.frames[0], 0.0), Error);
  EXPECT_THROW(forward_kinematics(clip.skeleton, clip.frames[0], std::nan("")), Error);
  BvhLocalPose short_pose = clip.frames[0];
  short_pose.translation.pop_back();
  EXPECT_THROW(forward_kinematics(clip.skeleton, short_pose, 0.01), Error);
}

TEST(BvhMalformed, MissingMotion) {
  std::string text = chain_text("Zrotation Yrotation Xrotation", {});
  text = text.substr(0, text.find("MOTION"));
  expect_rejected(text, 21, ErrorCode::kInvalidArgument);  // the file's last line
}

TEST(BvhMalformed, WrongChannelCountOnFrameLine) {
  expect_rejected(chain_text("Zrotation Yrotation Xrotation", {"0 0 0 0 0 0 0 0 0 0 0 0", "0 0 0 0 0 0 0 0 0 0 0"}),
                  kFirstFrameLine + 1, ErrorCode::kInvalidArgument);
  expect_rejected(chain_text("Zrotation Yrotation Xrotation", {"0 0 0 0 0 0 0 0 0 0 0 0 0"}), kFirstFrameLine,
                  ErrorCode::kInvalidArgument);
}

TEST(BvhMalformed, NonNumericValues) {
  expect_rejected(chain_text("Zrotation Yrotation Xrotation", {"0 0 0 0 0 abc 0 0 0 0 0 0"}), kFirstFrameLine,
                  ErrorCode::kInvalidArgument);
  expect_rejected(chain_text("Zrotation Yrotation Xrotation", {"0 0 0 0 0 1.5x 0 0 0 0 0 0"}), kFirstFrameLine,
                  ErrorCode::kInvalidArgument);
  expect_rejected(chain_text("Zrotation Yrotation Xrotation", {"0 0 0 0 0 nan 0 0 0 0 0 0"}), kFirstFrameLine,
                  ErrorCode::kInvalidArgument);
  expect_rejected(chain_text("Zrotation Yrotation Xrotation", {"0 0 0 inf 0 0 0 0 0 0 0 0"}), kFirstFrameLine,
                  ErrorCode::kInvalidArgument);
  expect_rejected(chain_text("Zrotation Yrotation Xrotation", {"0 0 0 +-5 0 0 0 0 0 0 0 0"}), kFirstFrameLine,
                  ErrorCode::kInvalidArgument);
  expect_rejected(chain_text("Zrotation Yrotation Xrotation", {"0 0 0 + 0 0 0 0 0 0 0 0"}), kFirstFrameLine,
                  ErrorCode::kInvalidArgument);
  EXPECT_EQ(parse_bvh(chain_text("Zrotation Yrotation Xrotation", {"+1 0 0 0 0 0 0 0 0 0 0 1e1"}))
                .frames[0]
                .translation[0]
                .x(),
            1.0);
  std::string text = chain_text("Zrotation Yrotation Xrotation", {"0 0 0 0 0 0 0 0 0 0 0 0"});
  text.replace(text.find("OFFSET 0 10 0"), 13, "OFFSET 0 ten 0");
  expect_rejected(text, 8, ErrorCode::kInvalidArgument);
}

TEST(BvhMalformed, UnknownOrBadChannels) {
  expect_rejected(chain_text("Zrotation Wrotation Xrotation", {"0 0 0 0 0 0 0 0 0 0 0 0"}), 9,
                  ErrorCode::kInvalidArgument);
  expect_rejected(chain_text("Zrotation Zrotation Xrotation", {"0 0 0 0 0 0 0 0 0 0 0 0"}), 9,
                  ErrorCode::kInvalidArgument);
  std::string text = chain_text("Zrotation Yrotation Xrotation", {"0 0 0 0 0 0 0 0 0 0 0 0"});
  text.replace(text.find("CHANNELS 3 Zrotation Yrotation Xrotation"), 10, "CHANNELS 7");
  expect_rejected(text, 9, ErrorCode::kInvalidArgument);
}

TEST(BvhMalformed, UnbalancedBraces) {
  std::string missing = chain_text("Zrotation Yrotation Xrotation", {"0 0 0 0 0 0 0 0 0 0 0 0"});
  missing.erase(missing.rfind("}\nMOTION"), 2);               // drop the root's closing brace (line 20)
  expect_rejected(missing, 20, ErrorCode::kInvalidArgument);  // MOTION moves up to line 20
  std::string extra = chain_text("Zrotation Yrotation Xrotation", {"0 0 0 0 0 0 0 0 0 0 0 0"});
  extra.insert(extra.find("MOTION"), "}\n");
  expect_rejected(extra, 21, ErrorCode::kInvalidArgument);
}

TEST(BvhMalformed, FrameTimeNotPositive) {
  for (const char* bad : {"0", "-0.01", "0.0"}) {
    std::string text = chain_text("Zrotation Yrotation Xrotation", {"0 0 0 0 0 0 0 0 0 0 0 0"});
    text.replace(text.find("Frame Time: 0.5"), 15, std::string("Frame Time: ") + bad);
    expect_rejected(text, 23, ErrorCode::kInvalidArgument);
  }
}

TEST(BvhMalformed, Truncated) {
  // Frames says 3, two lines follow: the error names the file's last line.
  std::string text =
      chain_text("Zrotation Yrotation Xrotation", {"0 0 0 0 0 0 0 0 0 0 0 0", "0 0 0 0 0 0 0 0 0 0 0 0"});
  text.replace(text.find("Frames: 2"), 9, "Frames: 3");
  expect_rejected(text, kFirstFrameLine + 2, ErrorCode::kDataLoss);  // the empty line after the last "\n"
  // Cut inside the hierarchy.
  const std::string full = chain_text("Zrotation Yrotation Xrotation", {"0 0 0 0 0 0 0 0 0 0 0 0"});
  expect_rejected(full.substr(0, full.find("JOINT Tip") + 9), 10, ErrorCode::kDataLoss);
  // Cut inside the last frame line: the line has too few values.
  expect_rejected(full.substr(0, full.size() - 8), kFirstFrameLine, ErrorCode::kInvalidArgument);
  // Empty input.
  expect_rejected("", 1, ErrorCode::kDataLoss);
}

TEST(BvhMalformed, ExtraFrameLines) {
  std::string text =
      chain_text("Zrotation Yrotation Xrotation", {"0 0 0 0 0 0 0 0 0 0 0 0", "0 0 0 0 0 0 0 0 0 0 0 0"});
  text.replace(text.find("Frames: 2"), 9, "Frames: 1");
  expect_rejected(text, kFirstFrameLine + 1, ErrorCode::kInvalidArgument);
}

TEST(BvhMalformed, MissingFile) {
  try {
    load_bvh("/nonexistent/clip.bvh");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kNotFound);
  }
}

// Every prefix of a valid file, and the file with any one byte replaced, either parses or is
// rejected with posefuse::Error: never a crash, a hang or another exception type.
TEST(BvhMalformed, EveryPrefixAndByteFlipRejectedCleanly) {
  const std::string full =
      chain_text("Zrotation Yrotation Xrotation", {"1 2 3 10 20 30 1 2 3 4 5 6", "1 2 3 10 20 30 1 2 3 4 5 6"});
  int parsed = 0;
  for (std::size_t n = 0; n < full.size(); ++n) {
    try {
      parse_bvh(full.substr(0, n));
      ++parsed;
    } catch (const Error&) {
    }
  }
  // Only cuts inside the last number of the last line (or its newline) still parse.
  EXPECT_LE(parsed, 3);
  for (std::size_t i = 0; i < full.size(); ++i) {
    for (char c : {'\0', '{', '}', 'x', '-', '\n', ' '}) {
      std::string changed = full;
      changed[i] = c;
      try {
        parse_bvh(changed);
      } catch (const Error&) {
      }
    }
  }
}
