#pragma once
// BVH motion capture: parsing any rig, forward kinematics into our world frame W, resampling.
//
// A BVH file is a joint hierarchy (offsets in the file's length unit, channels per joint in
// the order the file declares them) followed by one line of channel values per frame.
// Conventions we rely on (they are what MotionBuilder and the CMU exports write):
// - Rotation channels are degrees. A joint's local rotation is the product of its rotation
//   channels in the declared order: "Zrotation Yrotation Xrotation" gives
//   parent_from_joint = Rz * Ry * Rx.
// - Position channels (usually only on the root) are added to the joint's OFFSET.
// - The file's world frame M is Y up. We map it to W (z up) by the fixed rotation
//   W_from_M = +90 degrees about x: M's y becomes W's z, M's z becomes W's -y, x stays x.
//   Which way the subject faces in W is then whatever the clip has; a caller that needs a
//   heading rotates the result about W's z.
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "geometry/quaternion.hpp"

namespace posefuse::sim {

using geometry::Quat;
using geometry::Vec3;

enum class BvhChannel { kXposition, kYposition, kZposition, kXrotation, kYrotation, kZrotation };

struct BvhJoint {
  std::string name;
  int parent = -1;                      // index into BvhSkeleton::joints; -1 for the root
  Vec3 offset = Vec3::Zero();           // file units, in the parent's frame
  std::vector<BvhChannel> channels;     // in declared order
  int first_channel = 0;                // index of channels[0] within a frame line
  std::optional<Vec3> end_site_offset;  // file units, in this joint's frame ("End Site")
};

struct BvhSkeleton {
  std::vector<BvhJoint> joints;  // file order: every parent precedes its children
  int channel_count = 0;         // values per frame line

  // Index of the joint named `name`, or -1.
  int find(std::string_view name) const;
};

// One frame decoded from its channel values: what each joint's channels say, as rotations and
// translations in the joint's parent frame (file units).
struct BvhLocalPose {
  std::vector<Quat> parent_from_joint;  // identity for joints without rotation channels
  std::vector<Vec3> translation;        // sum of position channels; zero without them
};

struct BvhClip {
  BvhSkeleton skeleton;
  double frame_time_s = 0.0;         // > 0
  std::vector<BvhLocalPose> frames;  // frame i is at time i * frame_time_s

  int frame_count() const { return static_cast<int>(frames.size()); }
  double duration_s() const { return frames.empty() ? 0.0 : (frame_count() - 1) * frame_time_s; }
};

// Parses a whole BVH text. Throws posefuse::Error naming `source_name` and the line:
// field "<source_name>:<line>", kInvalidArgument for malformed content (missing MOTION,
// unbalanced braces, unknown channel, wrong value count on a frame line, non-numeric or
// non-finite values, Frame Time <= 0), kDataLoss for a file that ends early (fewer frame
// lines than "Frames:" says, hierarchy cut off).
BvhClip parse_bvh(std::string_view text, const std::string& source_name = "bvh");

// Reads and parses a file; kNotFound if it cannot be read.
BvhClip load_bvh(const std::filesystem::path& path);

// W_from_M: the fixed rotation from the BVH world (Y up) to W (Z up), see above.
Quat W_from_bvh_world();

// World pose of every joint at one frame, in W and metres.
struct BvhWorldPose {
  std::vector<Quat> W_from_joint;                   // per joint
  std::vector<Vec3> p_W_m;                          // joint origins
  std::vector<std::optional<Vec3>> end_site_p_W_m;  // per joint; set where it has an End Site
};

// Forward kinematics: M_from_joint = M_from_parent * parent_from_joint,
// p_M(joint) = p_M(parent) + M_from_parent * (offset + translation); then W_from_M and
// `metres_per_unit` (0.01 for centimetre files) map into W. Throws kInvalidArgument if the
// pose does not match the skeleton or metres_per_unit is not positive and finite.
BvhWorldPose forward_kinematics(const BvhSkeleton& skeleton, const BvhLocalPose& pose, double metres_per_unit);

// The clip resampled at `rate_hz`: frames at k / rate_hz for every k with k / rate_hz <=
// duration. Rotations are slerped (shortest arc), translations interpolated linearly, both
// between the two nearest source frames. Throws kInvalidArgument for rate_hz not > 0 or a
// clip without frames.
BvhClip resample(const BvhClip& clip, double rate_hz);

}  // namespace posefuse::sim
