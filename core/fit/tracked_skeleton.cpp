#include "fit/tracked_skeleton.hpp"

namespace posefuse::fit {

TrackedSkeleton TrackedSkeleton::all_tracked(const KinectSkeleton& positions_K) {
  TrackedSkeleton s;
  s.positions_K = positions_K;
  s.tracking.fill(JointTracking::kTracked);
  return s;
}

std::string joint_unusable_reason(const TrackedSkeleton& skeleton, int joint, bool accept_inferred) {
  const std::string name = kinect_joint_name(joint);
  switch (skeleton.tracking[joint]) {
    case JointTracking::kNotTracked: return name + " is not tracked";
    case JointTracking::kInferred:
      if (!accept_inferred) return name + " is inferred";
      break;
    case JointTracking::kTracked: break;
  }
  if (!skeleton.positions_K[joint].allFinite()) return name + " is not finite";
  return "";
}

}  // namespace posefuse::fit
