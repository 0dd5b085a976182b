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
#include "raycast/depth_camera.hpp"

namespace posefuse::fit {

// A camera joint reported TRACKED that lies farther than this from the fitted SMPL joint it is
// (shoulders, elbows, wrists, hands, spine, hips, legs; not the hand tips, thumbs and head the fit
// derives): the camera and the fit disagree by more than the camera's own error explains, and
// nothing in the frame says which is wrong (a fit folded into a wrong pose, or a camera joint gone
// off track), so the camera's tracking does not vouch for the fitted joint. 0.29 m: the 99.99th
// percentile of a 3-D normal error whose mean is 101 mm, the largest published mean error of the
// Kinect v2's upper-limb joints (paper 2's introduction, citing Wang et al. 2015;
// docs/simulator.md). A minute at 30 Hz has about 10^4 tracked arm joint values, so a camera as
// good as published raises about one flag a session, where the 99.9th percentile (0.255 m)
// would raise ten. The fit's own error (about 20 mm) adds little.
inline constexpr double kCameraDisagreementM = 0.29;

// A frame fitted at an energy above the tracker's trusted_energy matched its depth and silhouette
// less well than the fits measured to stay within a confident value's 15 degrees: on the
// joint-angle bench's tuning sessions (docs/benchmarks.md, "Fit energy and confidence") the
// confident angle values of frames fitted at 10 < E <= 100 reach a 99 % error bound of 47.0 degrees
// (pooled over the angles read from the joints). So such a frame's joints and forearms take at
// most the confidence of that bound, 2^-(47.0/15)^2 = 0.0011 (untrusted_fit_confidence).
inline constexpr double kUntrustedFitBound99Deg = 47.0;
double untrusted_fit_confidence();

struct FittedJoint {
  Eigen::Vector3d p_K = Eigen::Vector3d::Zero();
  // 1 where the camera tracks the corresponding joint within kCameraDisagreementM, 0 where it
  // tracks it farther away or where the fitted joint lies outside the camera's view; where it
  // does not track it, 0 for a wrist or hand and 0.5 for the others (docs/fitting.md, "Joint
  // confidence"). An SMPL joint with no camera joint (spine1, spine3, the collars, the head)
  // takes the lowest of the nearest ones around it in the kinematic tree.
  double confidence = 0.0;
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
  // Camera joints reported TRACKED but farther than kCameraDisagreementM from the SMPL joint they
  // are: those fitted joints have no confidence.
  int joints_off_camera = 0;
  // Fitted camera joints outside the depth image: neither the depth, the silhouette nor the
  // camera's skeleton sees them, so they have no confidence.
  int joints_out_of_view = 0;
};

// Caps every joint's and forearm's confidence at `cap`.
void cap_confidence(FittedBodyFrame& frame, double cap);

// The forearm orientations K_from_F (paper 1's F: y from elbow to wrist) at one frame.
struct ForearmOrientationPair {
  std::optional<Eigen::Quaterniond> left, right;
};

// The output for pose `theta` of a frame: joints from `rest_joints` (fit::rest_joints of the
// shape), confidences from `skeleton`'s tracking states, its distance to the fit and whether the
// fitted joint lies in `camera`'s image, forearms from `K_from_F`.
FittedBodyFrame make_fitted_body_frame(const Eigen::Matrix3Xd& rest_joints, const body::PoseLayout& layout,
                                       const Eigen::VectorXd& theta, const TrackedSkeleton& skeleton,
                                       const raycast::DepthCamera& camera, const ForearmOrientationPair& K_from_F);

}  // namespace posefuse::fit
