#pragma once
// The camera SDK's 25-joint skeleton of one frame as the fitter consumes it: positions in K and
// the SDK's tracking state per joint (Kinect v2 JointType order, as SkeletonFrame and
// zone_sampling's KinectSkeleton).
#include <array>
#include <string>

#include "fit/zone_sampling.hpp"

namespace posefuse::fit {

enum KinectJoint : int {
  kSpineBase = 0, kSpineMid, kNeck, kHead, kShoulderLeft, kElbowLeft, kWristLeft, kHandLeft,
  kShoulderRight, kElbowRight, kWristRight, kHandRight, kHipLeft, kKneeLeft, kAnkleLeft, kFootLeft,
  kHipRight, kKneeRight, kAnkleRight, kFootRight, kSpineShoulder, kHandTipLeft, kThumbLeft,
  kHandTipRight, kThumbRight,
};

// Kinect v2 JointType names ("SpineBase", ...), for messages.
const char* kinect_joint_name(int joint);

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
