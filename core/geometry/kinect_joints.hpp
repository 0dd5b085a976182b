#pragma once
// The Kinect v2 camera skeleton's 25 joints (the SDK's JointType order), the one enum and name
// table every part of posefuse uses: session chunks (SkeletonFrame.joints), the simulator's
// camera skeleton, the body fit and the forearm stage.
#include <array>

namespace posefuse::geometry {

inline constexpr int kKinectJointCount = 25;

enum KinectJoint : int {
  kSpineBase = 0,
  kSpineMid,
  kNeck,
  kHead,
  kShoulderLeft,
  kElbowLeft,
  kWristLeft,
  kHandLeft,
  kShoulderRight,
  kElbowRight,
  kWristRight,
  kHandRight,
  kHipLeft,
  kKneeLeft,
  kAnkleLeft,
  kFootLeft,
  kHipRight,
  kKneeRight,
  kAnkleRight,
  kFootRight,
  kSpineShoulder,
  kHandTipLeft,
  kThumbLeft,
  kHandTipRight,
  kThumbRight,
};

// JointType names, in JointType order (skeleton.csv's joint_name column, messages).
inline constexpr std::array<const char*, kKinectJointCount> kKinectJointNames = {
    "SpineBase",   "SpineMid",      "Neck",         "Head",       "ShoulderLeft", "ElbowLeft", "WristLeft",
    "HandLeft",    "ShoulderRight", "ElbowRight",   "WristRight", "HandRight",    "HipLeft",   "KneeLeft",
    "AnkleLeft",   "FootLeft",      "HipRight",     "KneeRight",  "AnkleRight",   "FootRight", "SpineShoulder",
    "HandTipLeft", "ThumbLeft",     "HandTipRight", "ThumbRight"};

// The joint's name, or "(no such joint)" outside 0..24.
inline const char* kinect_joint_name(int joint) {
  return joint >= 0 && joint < kKinectJointCount ? kKinectJointNames[static_cast<std::size_t>(joint)]
                                                 : "(no such joint)";
}

// Shoulder, elbow and wrist of one arm.
struct KinectArmJoints {
  KinectJoint shoulder, elbow, wrist;
};
inline constexpr KinectArmJoints kLeftArmJoints{kShoulderLeft, kElbowLeft, kWristLeft};
inline constexpr KinectArmJoints kRightArmJoints{kShoulderRight, kElbowRight, kWristRight};

}  // namespace posefuse::geometry
