#pragma once
// One fitted (and smoothed) pose as the body tracker's output (docs/fitting.md, "Body-fit stage",
// step 6): the 24 SMPL joints, the 25 camera-compatible joints, each forearm's IMU orientation
// turned onto the fitted forearm axis with its roll (II-B), the fit energy.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <vector>

#include "body/pose_parameters.hpp"
#include "fit/arm_roll.hpp"
#include "fit/tracked_skeleton.hpp"

namespace posefuse::fit {

struct FittedJoint {
  Eigen::Vector3d p_K = Eigen::Vector3d::Zero();
  double confidence = 0.0;  // 1 where the camera tracks the corresponding joint; else 0 for a wrist
                            // or hand, 0.5 for the others (docs/fitting.md, "Joint confidence")
};

struct FittedForearm {
  ArmSide side = ArmSide::kLeft;
  Eigen::Quaterniond K_from_F = Eigen::Quaterniond::Identity();  // y along the fitted forearm
  double pronation_rad = 0.0;
  double confidence = 0.0;  // the camera wrist's; 0 where the roll is undefined
};

struct FittedBodyFrame {
  std::int64_t t_us = 0;
  double energy = 0.0;                           // paper 2 eq. 4, the winning start's
  bool lost = false;                             // energy above the tracker's lost_energy
  bool imu_used = false;                         // a forearm direction entered the fit (imu term, eq. 9-11)
  std::vector<FittedJoint> smpl_joints;          // body::kNumJoints
  std::vector<FittedJoint> camera_joints;        // kKinectJointCount
  std::vector<Eigen::Quaterniond> K_from_joint;  // global rotation per SMPL joint (rest T-pose: identity)
  std::vector<FittedForearm> forearms;           // left then right, those with an orientation
};

// The forearm orientations K_from_F (paper 1's F: y from elbow to wrist) at one frame.
struct ForearmOrientationPair {
  std::optional<Eigen::Quaterniond> left, right;
};

// The output for pose `theta` of a frame: joints from `rest_joints` (fit::rest_joints of the
// shape), confidences from `skeleton`'s tracking states, forearms from `K_from_F`.
FittedBodyFrame make_fitted_body_frame(const Eigen::Matrix3Xd& rest_joints, const body::PoseLayout& layout,
                                       const Eigen::VectorXd& theta, const TrackedSkeleton& skeleton,
                                       const ForearmOrientationPair& K_from_F);

}  // namespace posefuse::fit
