#pragma once
// The whole frame calibration of paper 1, II-F, from one capture of the calibration panel held
// still at a few poses in front of the camera: at each pose the depth camera's IR and depth
// images, the mocap system's four marker positions (frame E), and the samples of an IMU fixed on
// the panel (axes visually aligned with P) and of the base IMU on the camera (B).
//
// Per pose: panel_in_camera (K_from_P and origin), the mocap markers (eqs. 4-6), and the static
// orientations W_from_P, W_from_B from each IMU's mean specific force and mean field by the
// vector observation (eq. 1, imu/vector_observation.hpp; what an orientation filter converges
// to on a still sensor). Then mocap_to_camera over all poses and base_imu_in_camera (eq. 8).
// Magnetometers must be calibrated beforehand (II-C): hard and soft iron bend the heading.
#include <string>
#include <vector>

#include "calib/frame_alignment.hpp"
#include "imu/imu_sample.hpp"

namespace posefuse::calib {

struct CapturePose {
  std::vector<std::uint16_t> ir;                    // camera.width x camera.height, row-major
  std::vector<std::uint16_t> depth_mm;              // same pixels
  std::array<Vec3, 4> markers_E{};                  // mocap, M0..M3
  std::vector<imu::ImuSample> panel_imu, base_imu;  // the hold at this pose
};

struct CalibrationCapture {
  PinholeCamera camera;
  PanelGeometry panel;
  std::vector<CapturePose> poses;
};

struct CaptureCalibrationOptions {
  int min_poses = 3;                  // eq. 8's spread needs several readings
  double min_pose_spread_rad = 0.17;  // the panel must be turned (about 10 degrees) between poses
  int min_imu_samples = 10;           // per IMU and pose
  PanelCameraOptions camera;
};

struct CapturePoseReport {
  PanelInCamera seen;
  Quat W_from_P = Quat::Identity(), W_from_B = Quat::Identity();
};

struct CaptureCalibration {
  MocapToCamera mocap;               // K_from_E, E_origin_K (eqs. 4-6)
  BaseImuAlignment base;             // K_from_B (eq. 8)
  Quat K_from_W = Quat::Identity();  // eq. 7 with the mean W_from_B of the capture
  double pose_spread_rad = 0.0;      // largest angle between two poses' K_from_P
  std::vector<CapturePoseReport> poses;
};

// Throws posefuse::Error naming the problem: kInvalidArgument "poses" (fewer than min_poses),
// "poses[i].panel_imu" / "poses[i].base_imu" (too few or bad samples); kFailedPrecondition
// "poses" (the panel hardly turned between poses: eq. 8's errors would not average),
// "poses[i].<field>" for what panel_in_camera refuses in pose i ("poses[2].ir": panel not found)
// and for a still IMU with no usable vector observation, and what mocap_to_camera and
// base_imu_in_camera refuse ("mocap.poses", "readings").
CaptureCalibration calibrate_capture(const CalibrationCapture& capture, const CaptureCalibrationOptions& options = {});

// The static orientation W_from_A of a still IMU: eq. 1 on its mean specific force and field.
// Throws kInvalidArgument `field` for too few or invalid samples, kFailedPrecondition `field`
// when the vector observation fails (no gravity, field along gravity).
Quat still_orientation(const std::vector<imu::ImuSample>& samples, const std::string& field, int min_samples);

}  // namespace posefuse::calib
