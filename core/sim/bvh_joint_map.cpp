#include "sim/bvh_joint_map.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <sstream>

#include "common/error.hpp"

namespace posefuse::sim {
namespace {

using namespace body;

// The 21-joint clips of ../shared/data/mocap (MotionBuilder names); Spine1 carries both spine2
// and the arms, spine3 stays unmapped.
constexpr std::string_view kMocap21 = R"(# posefuse BVH joint map: the 21-joint rig of ../shared/data/mocap
pelvis = Hips
left_hip = LeftUpLeg
right_hip = RightUpLeg
left_knee = LeftLeg
right_knee = RightLeg
left_ankle = LeftFoot
right_ankle = RightFoot
left_foot = LeftToeBase
right_foot = RightToeBase
spine1 = Spine
spine2 = Spine1
neck = Neck1
head = Head
left_collar = LeftShoulder
right_collar = RightShoulder
left_shoulder = LeftArm
right_shoulder = RightArm
left_elbow = LeftForeArm
right_elbow = RightForeArm
left_wrist = LeftHand
right_wrist = RightHand
)";

// CMU's 31-joint rig (LHipJoint/RHipJoint, Neck and the fingers stay unmapped).
constexpr std::string_view kCmu31 = R"(# posefuse BVH joint map: CMU's 31-joint rig
pelvis = Hips
left_hip = LeftUpLeg
right_hip = RightUpLeg
left_knee = LeftLeg
right_knee = RightLeg
left_ankle = LeftFoot
right_ankle = RightFoot
left_foot = LeftToeBase
right_foot = RightToeBase
spine1 = LowerBack
spine2 = Spine
spine3 = Spine1
neck = Neck1
head = Head
left_collar = LeftShoulder
right_collar = RightShoulder
left_shoulder = LeftArm
right_shoulder = RightArm
left_elbow = LeftForeArm
right_elbow = RightForeArm
left_wrist = LeftHand
right_wrist = RightHand
)";

bool same_name(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

std::string_view trim(std::string_view s) {
  const auto space = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  while (!s.empty() && space(s.front())) s.remove_prefix(1);
  while (!s.empty() && space(s.back())) s.remove_suffix(1);
  return s;
}

int smpl_index(std::string_view name) {
  const auto& names = smpl_joint_names();
  for (std::size_t j = 0; j < names.size(); ++j) {
    if (name == names[j]) return static_cast<int>(j);
  }
  return -1;
}

std::string mappable_names() {
  std::string out;
  for (int j = 0; j < kNumJoints; ++j) {
    if (j == kLeftHand || j == kRightHand) continue;
    out += std::string(out.empty() ? "" : ", ") + smpl_joint_names()[static_cast<std::size_t>(j)];
  }
  return out;
}

std::string at(const std::string& source, int line) { return source + ":" + std::to_string(line); }

}  // namespace

bool is_required_smpl_joint(int smpl) {
  switch (smpl) {
    case kPelvis:
    case kLeftHip:
    case kRightHip:
    case kLeftKnee:
    case kRightKnee:
    case kLeftAnkle:
    case kRightAnkle:
    case kHead:
    case kLeftShoulder:
    case kRightShoulder:
    case kLeftElbow:
    case kRightElbow:
    case kLeftWrist:
    case kRightWrist: return true;
    default: return false;
  }
}

const BvhJointMap& auto_bvh_joint_map() {
  static const BvhJointMap map = [] {
    BvhJointMap m;
    m.source = "auto";
    m.strict = false;
    // Order matters where candidates overlap (spine).
    m.entries = {
        {kPelvis, {"Hips", "hip", "pelvis", "Root"}, 0},
        {kLeftHip, {"LeftUpLeg", "LeftThigh", "lThigh", "LeftHip"}, 0},
        {kRightHip, {"RightUpLeg", "RightThigh", "rThigh", "RightHip"}, 0},
        {kLeftKnee, {"LeftLeg", "LeftShin", "lShin", "LeftKnee"}, 0},
        {kRightKnee, {"RightLeg", "RightShin", "rShin", "RightKnee"}, 0},
        {kLeftAnkle, {"LeftFoot", "lFoot", "LeftAnkle"}, 0},
        {kRightAnkle, {"RightFoot", "rFoot", "RightAnkle"}, 0},
        {kLeftFoot, {"LeftToeBase", "LeftToe", "lToe"}, 0},
        {kRightFoot, {"RightToeBase", "RightToe", "rToe"}, 0},
        {kSpine1, {"LowerBack", "Spine", "abdomen"}, 0},
        {kSpine2, {"Spine", "Spine1", "chest"}, 0},
        {kSpine3, {"Spine1", "Spine2", "chest2", "Chest"}, 0},
        {kNeck, {"Neck1", "Neck", "neck"}, 0},
        {kHead, {"Head"}, 0},
        {kLeftCollar, {"LeftShoulder", "LeftCollar", "lCollar"}, 0},
        {kRightCollar, {"RightShoulder", "RightCollar", "rCollar"}, 0},
        {kLeftShoulder, {"LeftArm", "LeftUpArm", "lShldr"}, 0},
        {kRightShoulder, {"RightArm", "RightUpArm", "rShldr"}, 0},
        {kLeftElbow, {"LeftForeArm", "LeftLowArm", "lForeArm"}, 0},
        {kRightElbow, {"RightForeArm", "RightLowArm", "rForeArm"}, 0},
        {kLeftWrist, {"LeftHand", "lHand"}, 0},
        {kRightWrist, {"RightHand", "rHand"}, 0},
    };
    return m;
  }();
  return map;
}

std::string_view bvh_joint_map_text(std::string_view builtin_name) {
  if (builtin_name == "mocap21") return kMocap21;
  if (builtin_name == "cmu31") return kCmu31;
  throw_invalid("bvh_joint_map", "'" + std::string(builtin_name) + "' is not a built-in joint map (mocap21, cmu31)");
}

BvhJointMap parse_bvh_joint_map(std::string_view text, const std::string& source) {
  BvhJointMap map;
  map.source = source;
  map.strict = true;
  std::array<int, kNumJoints> smpl_line{};
  int line = 0;
  while (!text.empty()) {
    ++line;
    const std::size_t end = std::min(text.find('\n'), text.size());
    std::string_view row = text.substr(0, end);
    text.remove_prefix(std::min(end + 1, text.size()));
    row = trim(row.substr(0, row.find('#')));
    if (row.empty()) continue;
    const std::size_t equals = row.find('=');
    if (equals == std::string_view::npos) {
      throw_invalid(at(source, line), "expected 'smpl_joint = BvhJointName', found '" + std::string(row) + "'");
    }
    const std::string smpl_name(trim(row.substr(0, equals)));
    const std::string bvh_name(trim(row.substr(equals + 1)));
    if (smpl_name.empty() || bvh_name.empty() || bvh_name.find_first_of(" \t=") != std::string::npos) {
      throw_invalid(at(source, line),
                    "expected 'smpl_joint = BvhJointName' (one name each side), found '" + std::string(row) + "'");
    }
    const int smpl = smpl_index(smpl_name);
    if (smpl < 0) {
      throw_invalid(at(source, line), "'" + smpl_name + "' is not an SMPL joint (known: " + mappable_names() + ")");
    }
    if (smpl == kLeftHand || smpl == kRightHand) {
      throw_invalid(at(source, line), "'" + smpl_name + "' cannot be mapped: SMPL's hands follow the wrists");
    }
    const auto su = static_cast<std::size_t>(smpl);
    if (smpl_line[su] != 0) {
      throw_invalid(at(source, line),
                    "'" + smpl_name + "' is mapped twice (first on line " + std::to_string(smpl_line[su]) + ")");
    }
    for (const BvhJointMapEntry& e : map.entries) {
      if (same_name(e.names.front(), bvh_name)) {
        throw_invalid(at(source, line), "BVH joint '" + bvh_name + "' already drives '" +
                                            smpl_joint_names()[static_cast<std::size_t>(e.smpl)] + "' (line " +
                                            std::to_string(e.line) + ")");
      }
    }
    smpl_line[su] = line;
    map.entries.push_back({smpl, {bvh_name}, line});
  }
  for (int j = 0; j < kNumJoints; ++j) {
    if (is_required_smpl_joint(j) && smpl_line[static_cast<std::size_t>(j)] == 0) {
      throw_invalid(source, std::string("no line for the required SMPL joint '") +
                                smpl_joint_names()[static_cast<std::size_t>(j)] + "'");
    }
  }
  return map;
}

BvhJointMap load_bvh_joint_map(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(ErrorCode::kNotFound, path.string(), "cannot open BVH joint-map file");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return parse_bvh_joint_map(buffer.str(), path.string());
}

BvhJointMap bvh_joint_map_named(const std::string& name_or_path) {
  if (name_or_path == "auto") return auto_bvh_joint_map();
  if (name_or_path == "mocap21" || name_or_path == "cmu31") {
    return parse_bvh_joint_map(bvh_joint_map_text(name_or_path), name_or_path);
  }
  return load_bvh_joint_map(name_or_path);
}

std::string bvh_joint_map_field(const BvhJointMap& map, int line) {
  return line > 0 ? at(map.source, line) : std::string("bvh.joints");
}

BvhJointMatch match_bvh_joint_map(const BvhJointMap& map, const BvhSkeleton& skeleton, bool check) {
  BvhJointMatch match;
  match.bvh_joint.fill(-1);
  match.line.fill(0);
  std::vector<bool> taken(skeleton.joints.size(), false);
  for (const BvhJointMapEntry& entry : map.entries) {
    const auto su = static_cast<std::size_t>(entry.smpl);
    for (const std::string& name : entry.names) {
      for (std::size_t b = 0; b < skeleton.joints.size(); ++b) {
        if (!taken[b] && same_name(skeleton.joints[b].name, name)) {
          match.bvh_joint[su] = static_cast<int>(b);
          match.line[su] = entry.line;
          taken[b] = true;
          break;
        }
      }
      if (match.bvh_joint[su] >= 0) break;
    }
    if (!check || match.bvh_joint[su] >= 0) continue;
    const std::string smpl_label = std::string("SMPL joint '") + smpl_joint_names()[su] + "'";
    if (map.strict) {
      throw_invalid(bvh_joint_map_field(map, entry.line),
                    "'" + entry.names.front() + "' (" + smpl_label + ") is not a joint of the BVH clip");
    }
    if (is_required_smpl_joint(entry.smpl)) {
      std::string names;
      for (const std::string& n : entry.names) names += (names.empty() ? "" : ", ") + n;
      throw_invalid("bvh.joints", "no joint for " + smpl_label + " (looked for " + names + ")");
    }
  }
  if (check) {
    for (int j = 0; j < kNumJoints; ++j) {
      if (is_required_smpl_joint(j) && match.bvh_joint[static_cast<std::size_t>(j)] < 0) {
        throw_invalid(map.source.empty() ? std::string("bvh.joints") : map.source,
                      std::string("the joint map has no entry for the required SMPL joint '") +
                          smpl_joint_names()[static_cast<std::size_t>(j)] + "'");
      }
    }
  }
  return match;
}

}  // namespace posefuse::sim
