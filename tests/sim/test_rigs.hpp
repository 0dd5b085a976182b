#pragma once
// BVH texts of two rigs for the retargeting tests, generated in code: the 21-joint rig of the
// shared mocap clips (MotionBuilder names, offsets of about a real subject in cm) and a
// CMU-31-like rig (the same body with CMU's zero-length LHipJoint/RHipJoint, LowerBack and Neck
// joints and the finger and thumb joints). Frame values are set per joint and channel by a
// callback, so tests can write random poses or move one joint alone.
#include <functional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace posefuse::sim::testing {

struct RigJointSpec {
  std::string name;
  int parent;
  double x, y, z;  // OFFSET
  bool root = false;
};

inline std::vector<RigJointSpec> rig21() {
  return {
      {"Hips", -1, 0, 0, 0, true},        {"LeftUpLeg", 0, 7.7, -10.1, 4.7},   {"LeftLeg", 1, 13.8, -38.0, 0},
      {"LeftFoot", 2, 14.5, -39.7, 0},    {"LeftToeBase", 3, 0.9, -2.4, 13.1}, {"RightUpLeg", 0, -7.4, -10.1, 4.7},
      {"RightLeg", 5, -14.4, -39.4, 0},   {"RightFoot", 6, -14.5, -39.8, 0},   {"RightToeBase", 7, -0.9, -2.6, 13.3},
      {"Spine", 0, 0.2, 11.5, -1.1},      {"Spine1", 9, 0.3, 11.6, -0.2},      {"Neck1", 10, -0.3, 9.9, 1.0},
      {"Head", 11, 0.6, 9.9, -0.7},       {"LeftShoulder", 10, 0, 0, 0},       {"LeftArm", 13, 19.0, 6.8, -1.8},
      {"LeftForeArm", 14, 28.1, 0, 0},    {"LeftHand", 15, 19.7, 0, 0},        {"RightShoulder", 10, 0, 0, 0},
      {"RightArm", 17, -17.7, 7.8, -2.3}, {"RightForeArm", 18, -29.6, 0, 0},   {"RightHand", 19, -19.4, 0, 0},
  };
}

inline std::vector<RigJointSpec> rig_cmu31() {
  return {
      {"Hips", -1, 0, 0, 0, true},
      {"LHipJoint", 0, 0, 0, 0},
      {"LeftUpLeg", 1, 7.7, -10.1, 4.7},
      {"LeftLeg", 2, 13.8, -38.0, 0},
      {"LeftFoot", 3, 14.5, -39.7, 0},
      {"LeftToeBase", 4, 0.9, -2.4, 13.1},
      {"RHipJoint", 0, 0, 0, 0},
      {"RightUpLeg", 6, -7.4, -10.1, 4.7},
      {"RightLeg", 7, -14.4, -39.4, 0},
      {"RightFoot", 8, -14.5, -39.8, 0},
      {"RightToeBase", 9, -0.9, -2.6, 13.3},
      {"LowerBack", 0, 0, 0, 0},
      {"Spine", 11, 0.2, 11.5, -1.1},
      {"Spine1", 12, 0.3, 11.6, -0.2},
      {"Neck", 13, 0, 0, 0},
      {"Neck1", 14, -0.3, 5.0, 0.5},
      {"Head", 15, 0.6, 4.9, -0.7},
      {"LeftShoulder", 13, 0, 0, 0},
      {"LeftArm", 17, 19.0, 6.8, -1.8},
      {"LeftForeArm", 18, 28.1, 0, 0},
      {"LeftHand", 19, 19.7, 0, 0},
      {"LeftFingerBase", 20, 4.0, 0, 0},
      {"LeftHandIndex1", 21, 3.0, 0, 0},
      {"LThumb", 20, 2.0, 0, 2.0},
      {"RightShoulder", 13, 0, 0, 0},
      {"RightArm", 24, -17.7, 7.8, -2.3},
      {"RightForeArm", 25, -29.6, 0, 0},
      {"RightHand", 26, -19.4, 0, 0},
      {"RightFingerBase", 27, -4.0, 0, 0},
      {"RightHandIndex1", 28, -3.0, 0, 0},
      {"RThumb", 27, -2.0, 0, 2.0},
  };
}

// value(frame, joint, channel): channels are X/Y/Z position (root only, channel 0..2) then
// Z, Y, X rotation in degrees (channel 3..5; 0..2 for other joints).
using RigValue = std::function<double(int frame, int joint, int channel)>;

inline std::string rig_text(const std::vector<RigJointSpec>& rig, int frames, double frame_time_s,
                            const RigValue& value) {
  std::ostringstream s;
  s.precision(12);
  std::function<void(int, int)> write = [&](int j, int depth) {
    const std::string pad(2 * static_cast<std::size_t>(depth), ' ');
    const RigJointSpec& r = rig[static_cast<std::size_t>(j)];
    s << pad << (r.root ? "ROOT " : "JOINT ") << r.name << "\n" << pad << "{\n";
    s << pad << "  OFFSET " << r.x << " " << r.y << " " << r.z << "\n";
    s << pad << "  CHANNELS " << (r.root ? "6 Xposition Yposition Zposition " : "3 ")
      << "Zrotation Yrotation Xrotation\n";
    bool leaf = true;
    for (std::size_t c = 0; c < rig.size(); ++c) {
      if (rig[c].parent == j) {
        write(static_cast<int>(c), depth + 1);
        leaf = false;
      }
    }
    if (leaf) s << pad << "  End Site\n" << pad << "  {\n" << pad << "    OFFSET 0 0 0\n" << pad << "  }\n";
    s << pad << "}\n";
  };
  s << "HIERARCHY\n";
  write(0, 0);
  s << "MOTION\nFrames: " << frames << "\nFrame Time: " << frame_time_s << "\n";
  for (int f = 0; f < frames; ++f) {
    bool first = true;
    for (std::size_t j = 0; j < rig.size(); ++j) {
      const int channels = rig[j].root ? 6 : 3;
      for (int c = 0; c < channels; ++c) {
        s << (first ? "" : " ") << value(f, static_cast<int>(j), c);
        first = false;
      }
    }
    s << "\n";
  }
  return s.str();
}

// The 21-joint rig with the right arm's offsets mirrored from the left (x -> -x), so that a
// mirrored pose of one arm is exactly the other arm's.
inline std::vector<RigJointSpec> symmetric_rig21() {
  auto rig = rig21();
  const auto find = [&](const std::string& name) -> RigJointSpec& {
    for (auto& j : rig) {
      if (j.name == name) return j;
    }
    throw std::runtime_error(name);
  };
  for (const char* side : {"Arm", "ForeArm", "Hand"}) {
    const auto& left = find(std::string("Left") + side);
    auto& right = find(std::string("Right") + side);
    right.x = -left.x;
    right.y = left.y;
    right.z = left.z;
  }
  return rig;
}

// `value` with frames first..last labelled the other way round, as a mocap solve that swaps the
// arms: each arm joint (Left*/Right* Shoulder, Arm, ForeArm, Hand) carries its mirror partner's
// channels mirrored (x -> -x turns Rz(a) Ry(b) Rx(c) into Rz(-a) Ry(-b) Rx(c)).
inline RigValue with_arms_swapped(const std::vector<RigJointSpec>& rig, RigValue value, int first, int last) {
  return [rig, value, first, last](int f, int j, int c) {
    const std::string& name = rig[static_cast<std::size_t>(j)].name;
    const bool left = name.rfind("Left", 0) == 0, right = name.rfind("Right", 0) == 0;
    const bool arm = name.find("Arm") != std::string::npos || name.find("Hand") != std::string::npos ||
                     name.find("Shoulder") != std::string::npos;
    if (f < first || f > last || !arm || !(left || right)) return value(f, j, c);
    const std::string partner = (left ? "Right" : "Left") + name.substr(left ? 4 : 5);
    int p = 0;
    while (rig[static_cast<std::size_t>(p)].name != partner) ++p;
    const double v = value(f, p, c);
    return c == 2 ? v : -v;
  };
}

}  // namespace posefuse::sim::testing
