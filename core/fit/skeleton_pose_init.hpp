#pragma once
// The analytic starting pose of paper 2, II-G: a pose "built analytically to replicate the Kinect
// skeleton", optimised next to the previous frame's result (the lower energy wins).
//
// Built segment by segment, root first, each from the camera joints it needs:
//   global     pelvis rotation (3 DOF) and translation: the rigid motion that best maps the model's
//              straight rest trunk (pelvis, spine2, hips, collar midpoint, shoulders) onto the
//              observed SpineBase, SpineMid, hips, SpineShoulder and shoulders (Kabsch, every usable
//              one of the 7; at least 3 not on one line). The long shoulder and spine baselines
//              keep the few-cm hip errors from turning the whole body.
//   spine      the rotation of the upper trunk that maps rest shoulder->shoulder and spine2->
//              (collar midpoint) onto ShoulderRight->ShoulderLeft and SpineMid->SpineShoulder,
//              relative to the pelvis, split equally between spine2 and spine3 (same axis, half the
//              angle each); spine1 stays 0 (the skeleton has no joint between pelvis and spine2).
//                                                     [SpineMid, SpineShoulder, ShoulderLeft, ShoulderRight]
//   neck       2-DOF swing that points the model's Head (head joint + head_above_skull_base_m
//              up the head) from the neck along Neck->Head; the head's own rotation is not
//              observable from one point and is kept.                                 [Neck, Head]
//   collars    2-DOF swing aiming the posed collar joint at the observed shoulder (scapular
//              elevation, paper 2 V-C.5).                                            [Shoulder*]
//   shoulders, elbows, wrists, hips (and knees in the full-body layout): 2-DOF swing aiming the
//              model's posed joint at the observed child joint (Elbow, Wrist, Hand, Knee, Ankle):
//              each built joint inherits the error of one observed joint rather than the sum of
//              the errors along the arm.
// A swing is the smallest rotation taking the rest bone (in the parent's posed frame) onto the
// target direction; its axis is perpendicular to the bone, so for a joint whose roll DOF paper 2
// removed (II-B) it lies in the plane of the two remaining DOF axes and is represented exactly.
// Each joint's limited DOFs are clamped into their limits (body/pose_parameters.cpp, eq. 8) as
// soon as it is built, so its children are aimed from the pose it really has (clamping at the
// end instead left wrists 13 cm off on the simulator's skeleton).
//
// Degrading: a segment whose joints are not tracked, not finite, inferred (unless
// accept_inferred_joints) or too close together keeps the previous frame's values for its DOFs
// and is listed in `fallbacks` with the reason naming the joint. Without a previous pose those
// DOFs stay at the rest pose, except the global pose: then the call throws.
#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "body/pose_parameters.hpp"
#include "body/smpl_model.hpp"
#include "fit/tracked_skeleton.hpp"

namespace posefuse::fit {

struct SkeletonInitOptions {
  // The SDK's guesses under occlusion are off by about 10 cm (and shoulders drop); the previous
  // frame is usually the better start for such a segment.
  bool accept_inferred_joints = false;
  // Where the camera skeleton's Head sits above SMPL's head joint (skull base), along the head's
  // up axis; 0.09 m is the simulator's camera skeleton (core/sim/camera_skeleton.hpp).
  double head_above_skull_base_m = 0.09;
  // Observed bones shorter than this give no direction.
  double min_bone_length_m = 0.02;
  bool clamp_to_limits = true;
};

enum class InitSegment {
  kGlobal,
  kSpine,
  kNeck,
  kLeftCollar,
  kRightCollar,
  kLeftShoulder,
  kRightShoulder,
  kLeftElbow,
  kRightElbow,
  kLeftWrist,
  kRightWrist,
  kLeftHip,
  kRightHip,
  kLeftKnee,
  kRightKnee,
};
const char* init_segment_name(InitSegment segment);

struct SegmentFallback {
  InitSegment segment;
  std::string reason;  // e.g. "ElbowLeft is inferred; kept the previous pose"
};

struct SkeletonInitResult {
  Eigen::VectorXd theta;
  std::vector<SegmentFallback> fallbacks;  // segments not built from this skeleton
  std::vector<int> clamped_dofs;           // DOF indices moved into their limits
  bool fell_back(InitSegment segment) const;
};

class SkeletonPoseInitializer {
 public:
  // beta: the subject's shape (personalisation). Throws posefuse::Error for a bad model, beta
  // ("beta") or options ("init_options.*").
  SkeletonPoseInitializer(std::shared_ptr<const body::SmplModel> model, body::PoseLayout layout,
                          const Eigen::VectorXd& beta, const SkeletonInitOptions& options = {});

  // previous_theta: the previous frame's pose (layout size), or empty for none (first frame,
  // recovery). Throws posefuse::Error: "skeleton" (kFailedPrecondition) when no joint is usable;
  // "skeleton.<Joint>" (kFailedPrecondition) when the global pose cannot be built and there is
  // no previous pose; "previous_theta" for a wrong size or non-finite values.
  SkeletonInitResult initialise(const TrackedSkeleton& skeleton, const Eigen::VectorXd& previous_theta) const;

  const body::PoseLayout& layout() const { return layout_; }
  const Eigen::Matrix3Xd& rest_joints() const { return rest_joints_; }

 private:
  std::shared_ptr<const body::SmplModel> model_;
  body::PoseLayout layout_;
  SkeletonInitOptions options_;
  Eigen::Matrix3Xd rest_joints_;  // 3 x 24 for the subject's beta
};

}  // namespace posefuse::fit
