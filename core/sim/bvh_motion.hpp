#pragma once
// A BVH clip as a whole-body motion of the simulated subject (BodyMotion, layout
// PoseLayout::all_joints(), room frame R): retargeted joint by joint (bvh_retarget.hpp), placed
// in the room and made smooth enough for IMU synthesis.
//
// Placement: the clip is scaled by the ratio of the template's leg length to the rig's
// (bvh_retarget.hpp), turned about the vertical so that the pelvis of the first frame faces +z
// (the camera of camera_session.hpp) when face_front is set, shifted so that the first frame's
// pelvis is above R's origin, and lifted so that the lowest ankle or foot joint over the whole
// clip is exactly as high as at rest (the feet touch the floor y = 0 at the clip's lowest
// moment).
// Smoothing: per joint the local rotations (quaternions on one hemisphere) and the
// translation are smoothed frame by frame with a zero-phase Gaussian of standard deviation
// smoothing_s (mocap noise of a few mm would otherwise reach the accelerometer as tens of
// m/s^2; see docs/simulator.md) and joined by a natural cubic spline, so the motion is C2 and
// passes near every frame. Outside the clip the spline continues along its end tangents (C2),
// so that an IMU's differentiation stencils at the clip's ends see no kink.
#include <Eigen/Core>

#include "body/template_generator.hpp"
#include "sim/body_motion.hpp"
#include "sim/bvh.hpp"
#include "sim/bvh_joint_map.hpp"

namespace posefuse::sim {

enum class BvhSmoothing {
  kGaussian,    // every channel by the Gaussian of smoothing_s
  kNoiseLevel,  // every channel by the cubic smoothing spline whose smoothing matches that
                // channel's own noise level (smoothing_spline.hpp); smoothing_s is not used
};

struct BvhMotionOptions {
  body::Sex sex = body::Sex::kMale;
  Eigen::VectorXd betas = Eigen::VectorXd::Zero(body::kTemplateNumBetas);
  BvhSmoothing smoothing = BvhSmoothing::kGaussian;
  double smoothing_s = 0.03;  // >= 0; see tests/sim/body_imu_test (MocapNoiseIsSmoothed...)
  bool face_front = true;
  BvhJointMap joint_map = auto_bvh_joint_map();  // which BVH joint drives which SMPL joint
};

// How the clip was placed: p_R = scale * R_from_bvh * p_bvh + offset_R_m for BVH joint
// positions p_bvh in file units (BVH world axes).
struct BvhPlacement {
  Quat R_from_bvh = Quat::Identity();
  double scale = 1.0;
  Vec3 offset_R_m = Vec3::Zero();
};

// Throws posefuse::Error for clips with fewer than 2 frames, rigs that cannot be mapped
// (bvh_retarget.hpp) and bad options. `placement`, when given, receives the placement.
BodyMotion bvh_motion(const BvhClip& clip, const BvhMotionOptions& options = {}, BvhPlacement* placement = nullptr);

}  // namespace posefuse::sim
