#pragma once
// The camera streams of a simulated recording: for a subject (sex, betas) and a pose sequence,
// depth, body index and skeleton chunks at the depth rate, with the room behind the person and
// the error models of depth_noise.hpp and camera_skeleton.hpp, plus the ground truth.
//
// Frames: the body model's canonical frame W (metres, y up, floor y = 0, see
// body/template_generator.hpp) is placed in the camera frame K by K_from_W. This "W" is the
// room frame R of room_frame.hpp (K_from_W here is K_from_R there), not the z-up world W of
// docs/architecture.md, "Frames"; W_from_R(heading) relates the two for the IMUs. The room is the
// floor y_W = 0 (a plane in K through K_from_W) and a wall facing the camera at z_K =
// wall_distance_m.
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "body/pose_parameters.hpp"
#include "body/template_generator.hpp"
#include "posefuse/v1/session.pb.h"
#include "raycast/depth_camera.hpp"
#include "sim/camera_skeleton.hpp"
#include "sim/depth_noise.hpp"
#include "sim/frame_truth.hpp"

namespace posefuse::sim {

// theta of `layout` at camera time t (seconds); rotations and translation in W.
using PoseSequence = std::function<Eigen::VectorXd(double t_s)>;

struct CameraSessionOptions {
  body::Sex sex = body::Sex::kMale;
  Eigen::VectorXd betas = Eigen::VectorXd::Zero(body::kTemplateNumBetas);
  raycast::DepthIntrinsics intrinsics;
  double rate_hz = 30.0;
  double duration_s = 1.0;
  // The camera 1 m above the floor, 2.5 m in front of the subject, facing them.
  Eigen::Isometry3d K_from_W =
      Eigen::Translation3d(0, -1.0, 2.5) * Eigen::AngleAxisd(3.14159265358979323846, Eigen::Vector3d::UnitY());
  double wall_distance_m = 4.0;
  DepthNoiseOptions depth_noise;
  CameraSkeletonOptions skeleton;
  std::uint32_t body_id = 0;
  std::uint64_t seed = 1;
  // Forearms whose ground truth (frame_truth.hpp: K_from_F, IMU pose, occlusion) is wanted.
  std::vector<ForearmStrap> forearm_straps;
};

struct CameraSessionResult {
  v1::SessionHeader header;                            // depth intrinsics and rate filled in
  std::vector<v1::SessionChunk> chunks;                // per frame: depth, body index, skeleton
  std::vector<std::int64_t> t_us;                      // frame times (camera clock)
  std::vector<Eigen::Matrix3Xd> true_camera_joints_K;  // error-free 25 joints per frame
  std::vector<FrameTruth> truth;                       // per frame: SMPL and camera joints, forearms of forearm_straps
};

// Copies intrinsics into a header's CameraIntrinsics (no tangential distortion).
void set_camera_intrinsics(const raycast::DepthIntrinsics& in, v1::CameraIntrinsics* out);

// Raises both arms sideways from hanging (-75 deg) to above the shoulders (+75 deg) and back,
// once per period, with the pelvis standing at the origin of W. For PoseLayout::full_body().
PoseSequence arm_raising_sequence(const body::PoseLayout& layout, double period_s);

// Throws posefuse::Error for bad options, or when the pose sequence returns a theta of the
// wrong size or non-finite values (naming the frame).
CameraSessionResult simulate_camera_session(const CameraSessionOptions& options, const body::PoseLayout& layout,
                                            const PoseSequence& poses);

}  // namespace posefuse::sim
