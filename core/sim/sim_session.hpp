#pragma once
// A whole simulated recording (issue 4): the camera streams (depth, body index, skeleton, RGB)
// of the body model with model mismatch, IMUs on both wrists and on the camera with their own
// clocks and packet loss, microphone audio with the buzzer stop, BLE broadcast receipts, and
// the ground truth of all of it (SimTruth, written as gt/ by ground_truth_files.hpp).
//
// Frames. Body: the body model's canonical frame (metres, y up, x to the subject's left, z to
// the front, floor y = 0; room_frame.hpp's R). W (docs/architecture.md, "Frames"): x magnetic
// north, y west, z up; the subject faces W's x turned by heading_rad about z:
// W_from_Body = W_from_R(heading_rad).
// K: the camera, placed facing the subject.
// F (forearm, paper 1 II-H, forearm_strap.hpp): origin at the strap centre on the elbow -> wrist
// line, y elbow -> wrist, x to the back of the hand; z to the thumb on the right arm and, F being
// right-handed, to the little finger on the left arm; F turns with the posed elbow joint, forearm
// roll included. A: the arm IMU, at +r along x_F, mounted by F_from_A. B: the base IMU fixed on
// the camera (K_from_B).
//
// Motion: select_motion (motion_library.hpp) by name, an exercise or a BVH clip. The arm IMUs'
// 1 kHz trajectories come from the same poses through the skeleton (skeleton_pose.hpp), so the
// IMU sits on the rendered strap.
//
// Chunks are emitted in approximately increasing time (session::chunk_order_key) to a
// ChunkSink as frames are rendered, so a 60 s session never sits in memory.
#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "body/template_generator.hpp"
#include "session/chunk_stream.hpp"
#include "sim/camera_skeleton.hpp"
#include "sim/color_render.hpp"
#include "sim/depth_noise.hpp"
#include "sim/imu_device.hpp"
#include "sim/motion_library.hpp"
#include "sim/panel_capture.hpp"
#include "sim/render_model.hpp"
#include "sim/soft_tissue.hpp"

namespace posefuse::sim {

// The IMU strap may slip on the skin: a smooth random turn about the forearm axis and slide
// along it, each a sum of slow sinusoids bounded by the maximum.
struct StrapSlipOptions {
  bool enabled = true;
  double max_rotation_rad = 3.0 * 3.14159265358979323846 / 180.0;
  double max_slide_m = 0.005;
  double period_s = 20.0;  // slowest component
};

struct SimSessionOptions {
  std::uint64_t seed = 1;
  double duration_s = 10.0;  // 1..3600
  // Set: the session lasts exactly as long as the motion (the whole BVH clip, or the exercise,
  // played at its speed) and duration_s is ignored; options file `duration_s = clip`.
  bool duration_from_motion = false;
  std::string motion = "arm_raising";  // motion_names(); "bvh" needs motion_options.bvh_path
  MotionOptions motion_options;
  body::Sex sex = body::Sex::kMale;
  Eigen::VectorXd betas = Eigen::VectorXd::Zero(body::kTemplateNumBetas);
  double heading_rad = 0.3;  // subject's facing, from magnetic north towards west
  // The subject's standing height as a clinic records it in the header (height_m): the body's own
  // (body/standing_height.hpp) plus a measurement error N(0, height_error_m^2) drawn from the seed
  // (a stadiometer's reading, posture, footwear); none in the header when record_height is off.
  bool record_height = true;
  double height_error_m = 0.01;  // 0..0.1

  // Camera: depth at depth_rate_hz; the colour camera at the same rate and instants.
  raycast::DepthIntrinsics depth_intrinsics;
  double depth_rate_hz = 30.0;
  double camera_height_m = 1.0;  // above the floor, looking at the subject
  // The camera's tilt: pitched down (> 0) or up about its left-right axis, then rolled about its
  // viewing axis (> 0: its y turns towards its x, the subject's right); -30..30 and -20..20 deg.
  double camera_pitch_deg = 0.0;
  double camera_roll_deg = 0.0;
  double subject_distance_m = 2.5;  // camera to the subject's pelvis, horizontally
  double wall_distance_m = 4.0;
  DepthNoiseOptions depth_noise;
  CameraSkeletonOptions skeleton;
  bool color = true;
  ColorCameraOptions color_camera;
  ClothingOptions clothing;
  SoftTissueOptions soft_tissue;  // wobble of the rendered surface under fast motion

  // IMUs: one per listed arm (0 left, 1 right) and the base on the camera.
  std::array<bool, 2> arm_imu = {true, true};
  // The header names each arm IMU for the other arm (a clinic's mix-up: the straps swapped, or
  // the devices paired the wrong way round). The truth keeps each device on its own arm.
  bool arm_imu_roles_swapped = false;
  double strap_to_elbow_m = 0.15;  // d_se
  double strap_radius_m = 0.035;   // r
  double mount_sigma_rad = 0.05;   // random F_from_A per arm, per-axis standard deviation
  StrapSlipOptions strap_slip;
  ImuDeviceOptions imu;               // rate, error model, packet loss (seeds are derived)
  double clock_offset_max_s = 100.0;  // device clock offsets drawn in [1, this]
  double clock_drift_max = 50e-6;     // and drifts in [-this, this]

  // Sync signals: the buzzer stops at buzzer_stop_s (camera clock, clamped into the session).
  double buzzer_stop_s = 1.5;
  double buzzer_repeat_s = 0.0;  // > 0: the buzzer stops again every this many s (0: once, paper 1)
  BuzzerOptions buzzer;          // stop_device_us is set from buzzer_stop_s
  AudioOptions audio;            // t_begin_s and duration_s are set to the session
  BleBroadcastOptions ble;

  PanelCaptureOptions panel_capture;  // not simulated here: posefuse-sim writes it beside the session

  int threads = 2;  // frames rendered in parallel (results do not depend on it)
  // How depth chunks are encoded: ZSTD_U16_LE (chunk files) or PNG16, which a recording
  // directory stores as is (its depth files), sparing the writer a decode and re-encode.
  v1::DepthFrame::Encoding depth_encoding = v1::DepthFrame::ZSTD_U16_LE;
};

// kInvalidArgument naming the field.
void validate(const SimSessionOptions& options);

// The options with the session's length settled: with duration_from_motion, duration_s becomes
// the motion's length (the motion is selected to learn it) and the flag is cleared;
// kInvalidArgument naming duration_s when that length is outside 1..3600 s.
SimSessionOptions with_session_duration(const SimSessionOptions& options);

struct SimDeviceTruth {
  std::string device_id;
  v1::ImuDevice::Role role = v1::ImuDevice::ROLE_UNSPECIFIED;
  DeviceClock clock;
  ImuErrors errors;
  std::vector<std::int64_t> t_device_us;  // every sample taken, lost or not
  std::vector<double> t_camera_s;
  std::vector<bool> lost;
  std::vector<Quat> W_from_A;        // true orientation per sample (A or B)
  std::vector<Vec3> gyr_bias_rad_s;  // true gyro bias per sample
  // Arm IMUs only (empty for the base): the forearm under the strap at each sample's true
  // camera time, K_from_F and pronation as in SimFrameTruth.
  std::vector<Quat> K_from_F;
  std::vector<double> pronation_rad;
};

struct SimArmTruth {
  int arm = 0;  // 0 left, 1 right
  bool has_imu = false;
  std::string device_id;
  double r_m = 0, d_se_m = 0, d_sw_m = 0, d_ul_m = 0;
  Quat F_from_A = Quat::Identity();  // mounting before slip
};

struct SimFrameTruth {
  std::int64_t t_us = 0;
  Eigen::Matrix3Xd smpl_joints_K;                    // 3 x 24
  Eigen::Matrix3Xd camera_joints_K;                  // 3 x 25, error-free
  std::array<Quat, 2> K_from_F;                      // per arm, from the body model
  std::array<Vec3, 2> strap_p_K;                     // F's origin per arm
  std::array<double, 2> pronation_rad{};             // twist about y_F relative to the rest pose; + pronation
  std::array<double, 2> forearm_visible_fraction{};  // of 5 points on elbow -> wrist, in the render
  std::array<bool, 2> strap_visible{};
  std::vector<Vec3> imu_p_K;     // per device in SimTruth::devices order
  std::vector<Quat> K_from_imu;  // per device, at the frame instant
};

// Thread CPU seconds per part of the work, summed over threads (for bench_sim_session).
using SimTimings = std::map<std::string, double>;

struct SimTruth {
  SimSessionOptions options;
  Eigen::Isometry3d K_from_Body = Eigen::Isometry3d::Identity();
  Quat W_from_Body = Quat::Identity();
  Quat K_from_W = Quat::Identity();
  Quat K_from_B = Quat::Identity();
  Vec3 camera_p_W_m = Vec3::Zero();
  std::vector<SimDeviceTruth> devices;  // arm IMUs (left, right as present), then the base
  std::array<SimArmTruth, 2> arms;
  Eigen::Matrix3Xd rest_joints;  // 3 x 24, Body frame, shaped
  std::vector<SimFrameTruth> frames;
  double buzzer_stop_camera_s = 0, buzzer_heard_camera_s = 0;
  std::vector<double> buzzer_later_stops_camera_s;  // SimSessionOptions::buzzer_repeat_s
  std::vector<double> ble_broadcast_camera_s;
  std::uint64_t chunks = 0;
  SimTimings cpu_s;
  std::vector<std::string> warnings;  // input repaired on the way (BodyMotion::warnings)
};

struct SimProgress {
  std::int64_t frames_done = 0;
  std::int64_t frames_total = 0;
};

// Streams header, data chunks and the end marker into `sink` (finish() is left to the caller).
// `progress` (optional) is called after every block of frames.
// truth.options has the session's length settled (with_session_duration).
SimTruth simulate_session(const SimSessionOptions& options, session::ChunkSink& sink,
                          const std::function<void(const SimProgress&)>& progress = {});

}  // namespace posefuse::sim
