#pragma once
// The camera SDK's 25-joint skeleton of one frame as the fitter consumes it: positions in K and
// the SDK's tracking state per joint (Kinect v2 JointType order, as SkeletonFrame and
// zone_sampling's KinectSkeleton).
#include <array>
#include <string>

#include "fit/zone_sampling.hpp"
#include "geometry/kinect_joints.hpp"

namespace posefuse::fit {

using geometry::kinect_joint_name;
using geometry::KinectJoint;
using enum geometry::KinectJoint;

enum class JointTracking { kNotTracked, kInferred, kTracked };

struct TrackedSkeleton {
  KinectSkeleton positions_K{};
  std::array<JointTracking, kKinectJointCount> tracking{};  // default: not tracked

  // Every joint tracked at the given positions.
  static TrackedSkeleton all_tracked(const KinectSkeleton& positions_K);
};

// Why a joint cannot be used: "" when it can. Not tracked, not finite, or inferred (unless
// `accept_inferred`).
std::string joint_unusable_reason(const TrackedSkeleton& skeleton, int joint, bool accept_inferred);

}  // namespace posefuse::fit
