#pragma once
// Rough shape estimation of paper 2, III-A: gradient descent on the betas so that the model's 7
// segment measurements match the camera skeleton's (eq. 18), with the paper's step rule (eq. 19):
// beta starts at 0, the step size lambda at 1; an update that does not lower E_s is rejected and
// halves lambda; the search stops when lambda < 0.01 (or after max_iterations, or when the
// gradient vanishes). Betas are kept within +-max_abs_beta. Measurements are averaged over the frames of the controlled
// pose.
//
// The controlled pose (paper 2, Fig. 3; the paper shows it but gives no numbers, these are ours):
// standing facing the camera, legs and arms straight, arms held away from the trunk so that the
// skeleton's arm joints are well placed. Every frame is checked; the first violation is reported
// with the frame and the joint or segment:
//   "calibration_frames[3].ElbowLeft"      not tracked / inferred / not finite / outside the image
//   "calibration_frames[3].pose.left_knee" bent 35 deg, at most 20 deg
#include <Eigen/Core>
#include <vector>

#include "body/smpl_model.hpp"
#include "fit/limb_bend.hpp"
#include "fit/segment_measurements.hpp"
#include "fit/tracked_skeleton.hpp"
#include "raycast/depth_camera.hpp"

namespace posefuse::fit {

struct ControlledPoseLimits {
  // Generous because the camera skeleton's own errors bend straight limbs.
  double max_knee_bend_deg = 30;
  // An elbow may look bent by this plus what the camera's arm joint error allows
  // at the elbow (bend_from_offset_deg, about 21 deg on an adult arm). Without it a straight arm's camera
  // elbow bent past 40 deg in every calibration frame of 17 of 96 simulated sessions (43-62 deg in
  // the first) and their personalisation was refused.
  double max_elbow_bend_deg = 40;
  double camera_arm_joint_error_m = kCameraJointErrorM;
  // Angle between an upper arm and the trunk's downward direction (shoulders -> hips).
  double min_arm_abduction_deg = 20, max_arm_abduction_deg = 100;
  // Angle of the shoulder line out of the image plane (0 = facing the camera squarely).
  double max_turn_deg = 30;
  // Every measured joint must project at least this far inside the image (when a camera is given).
  double image_margin_px = 2;
};

struct RoughShapeOptions {
  ControlledPoseLimits pose;
  double head_above_skull_base_m = 0.09;  // as SkeletonInitOptions
  // Unit of the lengths in E_s. The paper gives none, and its fixed-step rule depends on it: in
  // metres lambda = 1 is far too small a step (E_s's curvature along the weakest measured beta
  // is ~1e-4 m^2: 200,000 iterations leave beta 0.05 off), in centimetres far too large (lambda
  // halves below 0.01 before any step is accepted and beta stays 0). In decimetres the built-in
  // template converges to E_s ~ 1e-23 m^2 in ~57,000 iterations (0.2 s).
  double length_unit_m = 0.1;
  double initial_step = 1.0;  // lambda_0 (paper: 1)
  double min_step = 0.01;     // convergence when lambda falls below (paper: 0.01)
  int max_iterations = 200'000;
  double min_gradient_norm = 1e-12;  // stop when the (projected) gradient vanishes
  // Betas are kept in [-max_abs_beta, max_abs_beta] (projected gradient descent; not in the
  // paper): the camera skeleton's joint biases can otherwise push the shape far outside the
  // model's range (betas of -8 on the simulator's skeleton, see docs/benchmarks.md).
  double max_abs_beta = 3.0;
};

enum class RoughShapeStop { kStepBelowMinimum, kConverged, kMaxIterations };
const char* rough_shape_stop_name(RoughShapeStop stop);

struct RoughShapeResult {
  Eigen::VectorXd beta;
  SegmentLengths measured{};  // K_l, mean over the frames
  SegmentLengths model{};     // L_l(beta)
  double energy = 0;          // E_s(beta), m^2
  double initial_energy = 0;  // E_s(0)
  int iterations = 0;
  double final_step = 0;
  RoughShapeStop stop = RoughShapeStop::kMaxIterations;
  // Betas that no measurement depends on (zero gradient column): they stay 0 and are left to the
  // fine tuning (e.g. girths).
  std::vector<int> unconstrained_betas;
};

// Throws posefuse::Error naming the frame and joint or segment (see above) when a frame is not the
// controlled pose or the subject is not fully in view; "calibration_frames" when empty;
// "rough_options.*" or "pose_limits.*" for bad options. `camera` may be null (no image-border
// check).
void check_controlled_pose(const std::vector<TrackedSkeleton>& calibration_frames, const raycast::DepthCamera* camera,
                           const ControlledPoseLimits& limits = {});

RoughShapeResult estimate_rough_shape(const body::SmplModel& model,
                                      const std::vector<TrackedSkeleton>& calibration_frames,
                                      const raycast::DepthCamera* camera, const RoughShapeOptions& options = {});

}  // namespace posefuse::fit
