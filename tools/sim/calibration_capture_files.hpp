#pragma once
// The calibration_capture/ folder posefuse-sim writes beside a session when the options file
// says `panel_capture = true` (docs/simulator.md, "Calibration-panel capture"), read back by
// `posefuse-sim calibrate DIR`:
//   capture.txt            key = value: depth camera intrinsics (width height fx fy cx cy k1 k2 k3), poses
//   pose_<i>_ir.png        16-bit IR intensity, the depth camera's pixels
//   pose_<i>_depth.png     16-bit depth, mm (0 = no reading)
//   markers.csv            pose,marker,x_m,y_m,z_m: mocap marker centres M0..M3 in E
//   imu.csv                pose,device,t_us,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2,mx_uT,my_uT,mz_uT
//                          (device `panel`: the IMU on the panel, `base`: the base IMU on the camera)
//   preview.png            8-bit picture: per pose the IR (gamma 0.4) above the depth (near bright)
//   truth.json             the simulator's truth: K_from_E, E_origin_K, K_from_B, K_from_W, per pose K_from_P
// The panel is calib::PanelGeometry's default (docs/forearm.md).
#include <filesystem>
#include <string>

#include "calib/capture_calibration.hpp"
#include "sim/panel_capture.hpp"

namespace posefuse::tools {

void write_calibration_capture(const sim::PanelCaptureResult& capture, const std::filesystem::path& directory);

// Throws posefuse::Error naming the file (and line) for a missing or malformed file.
calib::CalibrationCapture read_calibration_capture(const std::filesystem::path& directory);

// calibrate_capture on a folder; errors name the pose's image files ("DIR/pose_2_ir.png: ir: ...").
calib::CaptureCalibration calibrate_capture_directory(const std::filesystem::path& directory);

// Human-readable result with residuals, ending in the header option the forearm stage takes:
//   forearm.K_from_B = w x y z
std::string calibration_report(const calib::CaptureCalibration& result);

}  // namespace posefuse::tools
