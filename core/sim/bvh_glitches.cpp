#include "sim/bvh_glitches.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <tuple>

#include "common/error.hpp"
#include "sim/option_checks.hpp"

namespace posefuse::sim {
namespace {

using Frames = std::vector<BvhLocalPose>;

std::string frame_range(int a, int b) { return "bvh.frames[" + std::to_string(a) + ".." + std::to_string(b) + "]"; }

std::string number(double value, const char* format = "%.3g") {
  char text[32];
  std::snprintf(text, sizeof text, format, value);
  return text;
}

// ---- arm swaps ----

struct ArmPair {
  std::vector<int> left, right;  // the two arm subtrees, paired joint by joint in file order
  int parent = -1;               // the joint both arms hang from
  int left_wrist = -1, right_wrist = -1;
  double arm_length = 0;  // rest shoulder -> wrist, file units
};

std::vector<int> subtree(const BvhSkeleton& skeleton, int root) {
  std::vector<int> out = {root};
  for (std::size_t j = static_cast<std::size_t>(root) + 1; j < skeleton.joints.size(); ++j) {
    const int parent = skeleton.joints[j].parent;
    if (std::find(out.begin(), out.end(), parent) != out.end()) out.push_back(static_cast<int>(j));
  }
  return out;
}

// The arm chains as the joint map names them (collar, else shoulder; wrist); none when the rig
// has no such pair.
std::optional<ArmPair> find_arms(const BvhSkeleton& skeleton, const BvhJointMap& joint_map) {
  using namespace body;
  const BvhJointMatch match = match_bvh_joint_map(joint_map, skeleton, false);
  const auto joint = [&](int smpl) { return match.bvh_joint[static_cast<std::size_t>(smpl)]; };
  ArmPair arms;
  const int left = joint(kLeftCollar) >= 0 ? joint(kLeftCollar) : joint(kLeftShoulder);
  const int right = joint(kRightCollar) >= 0 ? joint(kRightCollar) : joint(kRightShoulder);
  arms.left_wrist = joint(kLeftWrist);
  arms.right_wrist = joint(kRightWrist);
  if (left < 0 || right < 0 || arms.left_wrist < 0 || arms.right_wrist < 0) return std::nullopt;
  arms.parent = skeleton.joints[static_cast<std::size_t>(left)].parent;
  if (arms.parent < 0 || arms.parent != skeleton.joints[static_cast<std::size_t>(right)].parent) return std::nullopt;
  arms.left = subtree(skeleton, left);
  arms.right = subtree(skeleton, right);
  const auto in = [](const std::vector<int>& chain, int j) {
    return std::find(chain.begin(), chain.end(), j) != chain.end();
  };
  if (arms.left.size() != arms.right.size() || !in(arms.left, arms.left_wrist) || !in(arms.right, arms.right_wrist)) {
    return std::nullopt;
  }
  for (int j = arms.left_wrist; j != left; j = skeleton.joints[static_cast<std::size_t>(j)].parent) {
    arms.arm_length += skeleton.joints[static_cast<std::size_t>(j)].offset.norm();
  }
  if (!(arms.arm_length > 0)) return std::nullopt;
  return arms;
}

// The mirror x -> -x of the parent's frame, on a rotation and on a vector.
Quat mirrored(const Quat& q) { return Quat(q.w(), q.x(), -q.y(), -q.z()); }
Vec3 mirrored(const Vec3& v) { return Vec3(-v.x(), v.y(), v.z()); }

void swap_arms(const ArmPair& arms, BvhLocalPose& pose) {
  for (std::size_t i = 0; i < arms.left.size(); ++i) {
    const auto l = static_cast<std::size_t>(arms.left[i]);
    const auto r = static_cast<std::size_t>(arms.right[i]);
    const Quat left_rotation = pose.parent_from_joint[l];
    const Vec3 left_translation = pose.translation[l];
    pose.parent_from_joint[l] = mirrored(pose.parent_from_joint[r]);
    pose.translation[l] = mirrored(pose.translation[r]);
    pose.parent_from_joint[r] = mirrored(left_rotation);
    pose.translation[r] = mirrored(left_translation);
  }
}

// Wrists in the parent joint's frame: (left, right).
std::pair<Vec3, Vec3> wrists(const BvhSkeleton& skeleton, const ArmPair& arms, const BvhLocalPose& pose) {
  const BvhWorldPose world = forward_kinematics(skeleton, pose, 1.0);
  const auto p = static_cast<std::size_t>(arms.parent);
  const Quat P_from_W = world.W_from_joint[p].conjugate();
  return {P_from_W * (world.p_W_m[static_cast<std::size_t>(arms.left_wrist)] - world.p_W_m[p]),
          P_from_W * (world.p_W_m[static_cast<std::size_t>(arms.right_wrist)] - world.p_W_m[p])};
}

void repair_arm_swaps(const BvhSkeleton& skeleton, const BvhGlitchOptions& options, const BvhJointMap& joint_map,
                      Frames& frames, std::vector<BvhGlitch>& glitches) {
  const std::optional<ArmPair> arms = find_arms(skeleton, joint_map);
  if (!arms) return;
  const double min_jump = options.arm_swap_min_jump * arms->arm_length;
  bool swapped = false;
  int run_begin = 0;
  double run_jump = 0;
  Vec3 left, right;  // the previous frame's wrists, correctly labelled
  std::tie(left, right) = wrists(skeleton, *arms, frames[0]);
  const auto close_run = [&](int last) {
    BvhGlitch g;
    g.kind = BvhGlitchKind::kArmSwap;
    g.first_frame = run_begin;
    g.last_frame = last;
    g.joint = skeleton.joints[static_cast<std::size_t>(arms->left[0])].name + "/" +
              skeleton.joints[static_cast<std::size_t>(arms->right[0])].name;
    g.reason = "left and right arms swapped (the wrists jump " + number(run_jump) +
               " file units, exchanged and mirrored they continue the previous frame)";
    g.repair = "exchanging and mirroring the arms back";
    glitches.push_back(g);
  };
  for (std::size_t k = 1; k < frames.size(); ++k) {
    if (swapped) swap_arms(*arms, frames[k]);
    Vec3 l, r;
    std::tie(l, r) = wrists(skeleton, *arms, frames[k]);
    const double keep_left = (l - left).norm(), keep_right = (r - right).norm();
    const double toggle = (mirrored(r) - left).norm() + (mirrored(l) - right).norm();
    if (std::min(keep_left, keep_right) > min_jump && options.arm_swap_ratio * toggle < keep_left + keep_right) {
      swap_arms(*arms, frames[k]);
      std::swap(l, r);
      l = mirrored(l);
      r = mirrored(r);
      if (swapped) close_run(static_cast<int>(k) - 1);
      swapped = !swapped;
      run_begin = static_cast<int>(k);
      run_jump = std::min(keep_left, keep_right);
    }
    left = l;
    right = r;
  }
  if (swapped) close_run(static_cast<int>(frames.size()) - 1);
}

// ---- flips ----

void repair_flips(const BvhSkeleton& skeleton, double frame_time_s, const BvhGlitchOptions& options, Frames& frames,
                  std::vector<BvhGlitch>& glitches) {
  const double max_step = options.max_joint_rate_rad_s * frame_time_s;
  const int n = static_cast<int>(frames.size());
  for (std::size_t j = 0; j < skeleton.joints.size(); ++j) {
    const auto q = [&](int k) -> Quat& { return frames[static_cast<std::size_t>(k)].parent_from_joint[j]; };
    for (int a = 1; a < n; ++a) {
      const double jump = geometry::angle_between(q(a - 1), q(a));
      if (jump <= max_step) continue;
      // Frames a..b are the glitch when the step into b+1 jumps back: a-1 joins b+1 at a
      // possible rate and far closer than either jump. A glitch may also run to the last frame.
      // The jump as an offset in the joint's frame and in the parent's: a flip is usually one
      // fixed offset on the true rotation, which the step into b+1 undoes.
      const Quat jump_in_joint = q(a - 1).conjugate() * q(a);
      const Quat jump_in_parent = q(a) * q(a - 1).conjugate();
      int b = a;
      bool first_frame_is_the_glitch = false;
      while (b + 1 < n) {
        const double back = geometry::angle_between(q(b), q(b + 1));
        const double bridge = geometry::angle_between(q(a - 1), q(b + 1));
        const double undone = std::min(geometry::angle_between(q(b) * jump_in_joint.conjugate(), q(b + 1)),
                                       geometry::angle_between(jump_in_parent.conjugate() * q(b), q(b + 1)));
        const bool returns =
            (bridge <= max_step * (b - a + 2) && bridge < 0.5 * std::min(jump, back)) || undone <= 2.0 * max_step;
        if (back > max_step && returns) break;
        if (b - a + 1 >= options.max_glitch_frames) {
          // A jump out of frame 0 that never comes back: frame 0 is the odd one.
          if (a == 1) {
            first_frame_is_the_glitch = true;
            break;
          }
          throw_invalid(frame_range(a, b),
                        "joint " + skeleton.joints[j].name + " turns " + number(jump) + " rad in one frame (" +
                            number(jump / frame_time_s) + " rad/s, limit max_joint_rate_rad_s " +
                            number(options.max_joint_rate_rad_s) + ") and does not come back within " +
                            std::to_string(options.max_glitch_frames) +
                            " frames (max_glitch_frames; posefuse-sim: "
                            "bvh_max_glitch_frames); not repairable");
        }
        ++b;
      }
      BvhGlitch g;
      g.kind = BvhGlitchKind::kFlip;
      g.first_frame = a;
      g.last_frame = b;
      g.joint = skeleton.joints[j].name;
      g.reason = "rotation jumps " + number(jump) + " rad in one frame (" + number(jump / frame_time_s) +
                 (b + 1 < n ? " rad/s) and back" : " rad/s) up to the last frame");
      if (first_frame_is_the_glitch) {
        g.first_frame = g.last_frame = 0;
        g.reason = "rotation of the first frame is " + number(jump) + " rad from the next, which the clip continues";
        g.repair = "holding frame 1";
        glitches.push_back(g);
        q(0) = q(1);
        continue;
      }
      g.repair = b + 1 < n ? "slerp across the frames" : "holding frame " + std::to_string(a - 1);
      glitches.push_back(g);
      const Quat before = q(a - 1);
      const Quat after = b + 1 < n ? q(b + 1) : before;
      for (int k = a; k <= b; ++k) {
        const double u = static_cast<double>(k - a + 1) / static_cast<double>(b - a + 2);
        q(k) = before.slerp(u, after).normalized();
      }
      a = b + 1;
    }
  }
}

// ---- bone lengths ----

double median(std::vector<double> values) {
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

void repair_bone_lengths(const BvhSkeleton& skeleton, const BvhGlitchOptions& options, Frames& frames,
                         std::vector<BvhGlitch>& glitches) {
  const int n = static_cast<int>(frames.size());
  const std::size_t joints = skeleton.joints.size();
  const auto length = [&](int k, std::size_t j) {
    return (skeleton.joints[j].offset + frames[static_cast<std::size_t>(k)].translation[j]).norm();
  };
  std::vector<double> medians(joints, 0.0), nonzero;
  for (std::size_t j = 0; j < joints; ++j) {
    if (skeleton.joints[j].parent < 0) continue;
    std::vector<double> lengths(static_cast<std::size_t>(n));
    for (int k = 0; k < n; ++k) lengths[static_cast<std::size_t>(k)] = length(k, j);
    medians[j] = median(lengths);
    if (medians[j] > 0) nonzero.push_back(medians[j]);
  }
  if (nonzero.empty()) return;
  const double typical = median(nonzero);
  for (std::size_t j = 0; j < joints; ++j) {
    if (skeleton.joints[j].parent < 0) continue;
    const double tolerance = options.bone_length_tolerance * (medians[j] > 0 ? medians[j] : typical);
    const auto bad = [&](int k) { return std::abs(length(k, j) - medians[j]) > tolerance; };
    for (int a = 0; a < n; ++a) {
      if (!bad(a)) continue;
      int b = a;
      double worst = length(a, j);
      while (b + 1 < n && bad(b + 1)) {
        ++b;
        if (std::abs(length(b, j) - medians[j]) > std::abs(worst - medians[j])) worst = length(b, j);
      }
      if (b - a + 1 > options.max_glitch_frames) {
        throw_invalid(frame_range(a, b), "joint " + skeleton.joints[j].name + " is " + number(worst) +
                                             " file units from its parent (median " + number(medians[j]) + ") for " +
                                             std::to_string(b - a + 1) + " frames, more than max_glitch_frames " +
                                             std::to_string(options.max_glitch_frames) +
                                             " (posefuse-sim: bvh_max_glitch_frames); not repairable");
      }
      if (a == 0 && b == n - 1)
        throw_invalid(frame_range(a, b),
                      "joint " + skeleton.joints[j].name + " has no frame with its median bone length");
      BvhGlitch g;
      g.kind = BvhGlitchKind::kBoneLength;
      g.first_frame = a;
      g.last_frame = b;
      g.joint = skeleton.joints[j].name;
      g.reason = "bone length jumps to " + number(worst) + " file units (median " + number(medians[j]) + ")";
      g.repair = a > 0 && b + 1 < n
                     ? "interpolating the joint's translation across the frames"
                     : "holding the joint's translation of frame " + std::to_string(a > 0 ? a - 1 : b + 1);
      glitches.push_back(g);
      const Vec3 before = frames[static_cast<std::size_t>(a > 0 ? a - 1 : b + 1)].translation[j];
      const Vec3 after = frames[static_cast<std::size_t>(b + 1 < n ? b + 1 : a - 1)].translation[j];
      for (int k = a; k <= b; ++k) {
        const double u = static_cast<double>(k - a + 1) / static_cast<double>(b - a + 2);
        frames[static_cast<std::size_t>(k)].translation[j] = (1.0 - u) * before + u * after;
      }
      a = b;
    }
  }
}

}  // namespace

std::string describe(const BvhGlitch& glitch, double frame_time_s) {
  return "bvh frames " + std::to_string(glitch.first_frame) + ".." + std::to_string(glitch.last_frame) + " (" +
         number(glitch.first_frame * frame_time_s, "%.3f") + ".." + number(glitch.last_frame * frame_time_s, "%.3f") +
         " s), " + glitch.joint + ": " + glitch.reason + "; repaired by " + glitch.repair;
}

BvhRepair repair_bvh_glitches(const BvhClip& clip, const BvhGlitchOptions& options, const BvhJointMap& joint_map) {
  require_positive(options.max_joint_rate_rad_s, "max_joint_rate_rad_s");
  require_positive(options.bone_length_tolerance, "bone_length_tolerance");
  require_positive(options.arm_swap_min_jump, "arm_swap_min_jump");
  if (!(options.arm_swap_ratio > 1) || !std::isfinite(options.arm_swap_ratio)) {
    throw_invalid("arm_swap_ratio", "is " + std::to_string(options.arm_swap_ratio) + ", must be > 1");
  }
  if (options.max_glitch_frames < 1) throw_invalid("max_glitch_frames", "must be >= 1");
  require_positive(clip.frame_time_s, "clip.frame_time_s");
  BvhRepair out;
  out.clip = clip;
  if (clip.frames.size() < 2) return out;
  repair_arm_swaps(clip.skeleton, options, joint_map, out.clip.frames, out.glitches);
  repair_flips(clip.skeleton, clip.frame_time_s, options, out.clip.frames, out.glitches);
  repair_bone_lengths(clip.skeleton, options, out.clip.frames, out.glitches);
  return out;
}

}  // namespace posefuse::sim
