#include "fit/tracked_skeleton.hpp"

namespace posefuse::fit {

const char* kinect_joint_name(int joint) {
  static constexpr const char* kNames[kKinectJointCount] = {
      "SpineBase",  "SpineMid",  "Neck",      "Head",        "ShoulderLeft", "ElbowLeft",     "WristLeft",
      "HandLeft",   "ShoulderRight", "ElbowRight", "WristRight", "HandRight", "HipLeft",      "KneeLeft",
      "AnkleLeft",  "FootLeft",  "HipRight",  "KneeRight",   "AnkleRight",   "FootRight",     "SpineShoulder",
      "HandTipLeft", "ThumbLeft", "HandTipRight", "ThumbRight"};
  return joint >= 0 && joint < kKinectJointCount ? kNames[joint] : "(no such joint)";
}

TrackedSkeleton TrackedSkeleton::all_tracked(const KinectSkeleton& positions_K) {
  TrackedSkeleton s;
  s.positions_K = positions_K;
  s.tracking.fill(JointTracking::kTracked);
  return s;
}

std::string joint_unusable_reason(const TrackedSkeleton& skeleton, int joint, bool accept_inferred) {
  const std::string name = kinect_joint_name(joint);
  switch (skeleton.tracking[joint]) {
    case JointTracking::kNotTracked:
      return name + " is not tracked";
    case JointTracking::kInferred:
      if (!accept_inferred) return name + " is inferred";
      break;
    case JointTracking::kTracked:
      break;
  }
  if (!skeleton.positions_K[joint].allFinite()) return name + " is not finite";
  return "";
}

}  // namespace posefuse::fit
