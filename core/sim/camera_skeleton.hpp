#pragma once
// A camera-SDK-like 25-joint skeleton (Kinect v2) synthesised from a posed SMPL-format body,
// with the SDK's typical errors.
//
// Joint order: the Kinect v2 SDK's JointType enum (Kinect.h), as SkeletonFrame requires:
//   0 SpineBase  1 SpineMid  2 Neck  3 Head  4 ShoulderLeft  5 ElbowLeft  6 WristLeft
//   7 HandLeft  8 ShoulderRight  9 ElbowRight  10 WristRight  11 HandRight  12 HipLeft
//   13 KneeLeft  14 AnkleLeft  15 FootLeft  16 HipRight  17 KneeRight  18 AnkleRight
//   19 FootRight  20 SpineShoulder  21 HandTipLeft  22 ThumbLeft  23 HandTipRight  24 ThumbRight
// Mapping from SMPL joints: most joints have a direct counterpart (pelvis, spine2, neck, the
// shoulders, elbows, wrists, hands, hips, knees, ankles, feet); Head sits 9 cm up the head's
// y axis from SMPL's head joint (which is at the skull base), SpineShoulder midway between
// the collars, HandTip one wrist->hand length beyond the hand, Thumb 4 cm along the hand's z
// axis (the thumb side in SMPL's T-pose) from the middle of wrist and hand.
//
// Orientations follow the SDK's hierarchical convention: y along the bone from the parent
// joint, x and z taken from the SMPL rotation of the bone (Gram-Schmidt against y); the root
// (SpineBase) reports the pelvis rotation; end joints (Head, Feet, HandTips, Thumbs) report
// none (all zero), as the SDK does.
//
// Error model, in this order (all documented in CameraSkeletonOptions):
//  1. straight spine: SpineMid is moved onto the line SpineBase -> SpineShoulder (the SDK's
//     spine does not bend when the trunk tilts or curls);
//  2. occlusion: a joint whose projected pixel has a depth more than occlusion_margin_m
//     nearer than the joint (or that projects outside the image) is INFERRED and gets an
//     extra bias of inferred_error_m; an inferred shoulder drops by inferred_shoulder_drop_m
//     along `down_K`. The trunk's joints (SpineBase, SpineMid, SpineShoulder, Neck, the hips)
//     lie deeper in the body than the margin, so the trunk's own surface in front of one does
//     not hide it: only another part (an arm, a hand, the head) does. The SDK finds a joint
//     from the pixels of its own body part (Shotton et al. 2011), which the trunk shows;
//  3. a smooth per-joint bias of fixed length (upper-limb joints: uniform in
//     [upper_limb_bias_min_m, upper_limb_bias_max_m], other joints in [other_bias_min_m,
//     other_bias_max_m]) whose direction turns slowly (period bias_period_s) about a random
//     axis, plus white jitter N(0, jitter_sigma_m) per axis and frame;
//  4. jumps: in a frame, with jump_probability, one random upper-limb joint is displaced by
//     a length uniform in [jump_min_m, jump_max_m] in a random direction for that frame only;
//  5. hand flips: each hand's orientation is turned 180 deg about its bone (y) axis with
//     hand_flip_probability per frame.
// Deterministic for (seed, frame_index): the per-joint biases come from the seed alone, the
// per-frame draws from streams of (seed, frame_index), one stream per process so that switching
// one off does not change the others.
#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "body/body_evaluator.hpp"
#include "geometry/kinect_joints.hpp"
#include "posefuse/v1/session.pb.h"
#include "raycast/depth_camera.hpp"

namespace posefuse::sim {

inline constexpr int kCameraJointCount = geometry::kKinectJointCount;

// Parent of each camera joint in the SDK's hierarchy (-1 for SpineBase).
const std::array<int, kCameraJointCount>& camera_joint_parents();
// Shoulders, elbows, wrists, hands, hand tips and thumbs.
bool is_upper_limb(int camera_joint);

struct CameraSkeletonOptions {
  double upper_limb_bias_min_m = 0.05, upper_limb_bias_max_m = 0.10;
  double other_bias_min_m = 0.02, other_bias_max_m = 0.04;
  double bias_period_s = 10.0;
  double jitter_sigma_m = 0.004;
  double occlusion_margin_m = 0.12;  // a visible joint lies a few cm behind its surface
  double inferred_error_m = 0.10;
  double inferred_shoulder_drop_m = 0.05;
  Eigen::Vector3d down_K = -Eigen::Vector3d::UnitY();  // a level camera
  double jump_probability = 0.03;
  double jump_min_m = 0.15, jump_max_m = 0.30;
  double hand_flip_probability = 0.05;
};

void validate(const CameraSkeletonOptions& options);

// SMPL joints of a posed body in the camera frame K.
struct SmplJointsK {
  Eigen::Matrix3Xd positions_K;                                // 3 x 24
  std::array<Eigen::Matrix3d, body::kNumJoints> K_from_joint;  // global joint rotations
};
SmplJointsK smpl_joints_in_camera(const body::BodyEvaluator& evaluator, const Eigen::Isometry3d& K_from_W);

// The error-free 25 joints (positions in K) mapped from SMPL, before the error model.
Eigen::Matrix3Xd camera_joints_from_smpl(const SmplJointsK& smpl);

class CameraSkeletonSimulator {
 public:
  // `rendered` is the mesh whose faces the renders' face images index (its skinning weights
  // say which body part each face belongs to).
  CameraSkeletonSimulator(const raycast::DepthCamera& camera, const CameraSkeletonOptions& options, std::uint64_t seed,
                          const body::SmplModel& rendered);

  // One frame. depth_mm is the depth image the SDK sees (width x height of the camera, 0 =
  // nothing), face the subject's face seen at each pixel (-1: not the subject; RenderImages::face),
  // both used for the occlusion test. t_us is also the time of the slow bias.
  v1::SkeletonFrame simulate(const SmplJointsK& smpl, const std::vector<uint16_t>& depth_mm,
                             const std::vector<std::int32_t>& face, std::int64_t frame_index, std::int64_t t_us,
                             std::uint32_t body_id) const;

 private:
  raycast::DepthCamera camera_;
  CameraSkeletonOptions options_;
  std::uint64_t seed_;
  // Per joint: bias length, and an orthonormal pair spanning the plane the bias turns in.
  std::array<double, kCameraJointCount> bias_length_m_{};
  std::array<Eigen::Vector3d, kCameraJointCount> bias_u_, bias_v_, inferred_direction_;
  std::array<double, kCameraJointCount> bias_phase_{};
  std::vector<std::int8_t> joint_of_face_;  // the SMPL joint whose bone carries each face
};

}  // namespace posefuse::sim
