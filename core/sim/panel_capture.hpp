#pragma once
// The calibration-panel capture of paper 1, II-F: what the frame calibration sees before a
// session. The panel (calib/panel.hpp, frame P) is held still at a few poses in front of the
// camera, and at each pose:
//  (a) the mocap system measures its four marker centres in its frame E (Gaussian noise per axis);
//  (b) the depth camera (Kinect v2) gives an IR intensity image and a depth image, both ray cast
//      through Embree (raycast/mesh_scene.hpp): the board as a box, the markers as spheres, the
//      room's floor and back wall behind. IR: the active illumination falling off as
//      reflectivity * cos(incidence) / range^2, the retro-reflective markers returning far more
//      than the sensor's full scale (so every pixel they cover by more than about 1/8
//      saturates, as real marker blobs do), averaged over 3 x 3 rays per pixel, then shot and
//      read noise and 16-bit clipping. Depth: the pixel-centre render with the room and the
//      simulator's Kinect error model (sim/depth_noise.hpp: incidence dropout, flying pixels,
//      axial noise, mm quantisation); saturated (marker) pixels have no depth, as on the sensor.
//  (c) an IMU fixed on the panel (axes visually aligned with P, within imu_misalignment_deg)
//      and the base IMU on the camera sample the still hold (sim/imu_synth.hpp: noise, biases,
//      scale and misalignment; magnetometers calibrated beforehand, so no hard or soft iron).
// Truth: K_from_E and E's origin in K, K_from_B (the session's), each pose's K_from_P.
// Deterministic for (options, setup).
#include <array>
#include <cstdint>
#include <vector>

#include "calib/capture_calibration.hpp"
#include "raycast/depth_camera.hpp"
#include "sim/depth_noise.hpp"
#include "sim/imu_synth.hpp"

namespace posefuse::sim {

struct PanelCaptureOptions {
  bool enabled = false;                               // posefuse-sim writes calibration_capture/ when set
  int poses = 4;                                      // 1..20 random poses (ignored when poses_K is given)
  double distance_min_m = 1.3, distance_max_m = 1.9;  // panel centre from the camera
  double max_tilt_deg = 35.0;                         // turn about K's x and y, each uniform in +-this
  double max_roll_deg = 30.0;                         // turn in the panel plane
  double marker_noise_m = 0.0003;                     // mocap marker position noise, per axis sigma
  double imu_misalignment_deg = 0.5;                  // panel IMU on the panel, per axis sigma
  double hold_s = 1.0;                                // each pose held still this long
  double ir_gain = 20000.0;                           // IR counts of a facing white surface at 1 m
  std::vector<calib::PanelPose> poses_K;              // explicit poses (tests), else random ones
};

// kInvalidArgument naming the field ("panel_capture.<field>").
void validate(const PanelCaptureOptions& options);

// The rig the capture shares with the session it calibrates.
struct PanelCaptureRig {
  raycast::DepthIntrinsics depth_intrinsics;
  Quat K_from_W = Quat::Identity();
  Quat K_from_B = Quat::Identity();
  double camera_height_m = 1.0;
  double wall_distance_m = 4.0;
  DepthNoiseOptions depth_noise;
  double imu_rate_hz = 80.0;
  ImuSynthOptions imu;  // earth field, gravity, error model (hard/soft iron are zeroed)
  std::uint64_t seed = 1;
};

struct PanelCaptureTruth {
  Quat K_from_E = Quat::Identity();
  Vec3 E_origin_K = Vec3::Zero();  // eq. 6
  Quat K_from_B = Quat::Identity();
  Quat K_from_W = Quat::Identity();
  Quat P_from_panel_imu = Quat::Identity();  // the panel IMU's visual-alignment error
  std::vector<calib::PanelPose> K_from_P;    // per pose
  ImuErrors panel_imu_errors, base_imu_errors;
  double marker_noise_m = 0.0;
};

struct PanelCaptureResult {
  calib::CalibrationCapture capture;
  PanelCaptureTruth truth;
};

PanelCaptureResult simulate_panel_capture(const PanelCaptureOptions& options, const PanelCaptureRig& rig);

// The Kinect depth intrinsics as the calibration's pinhole camera (same model, no tangential terms).
geometry::PinholeCamera pinhole_of(const raycast::DepthIntrinsics& intrinsics);

}  // namespace posefuse::sim
