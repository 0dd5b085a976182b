#include "calib/capture_calibration.hpp"

#include <cmath>
#include <string>

#include "common/error.hpp"
#include "imu/vector_observation.hpp"

namespace posefuse::calib {

Quat still_orientation(const std::vector<imu::ImuSample>& samples, const std::string& field, int min_samples) {
  if (static_cast<int>(samples.size()) < min_samples) {
    throw_invalid(field, std::to_string(samples.size()) + " samples, need at least " + std::to_string(min_samples));
  }
  imu::validate_imu_stream(samples, field.c_str());
  Vec3 acc = Vec3::Zero(), mag = Vec3::Zero();
  int with_field = 0;
  for (const imu::ImuSample& s : samples) {
    acc += s.acc_m_s2;
    if (s.mag_uT.allFinite()) {
      mag += s.mag_uT;
      ++with_field;
    }
  }
  if (with_field == 0) throw_invalid(field, "no magnetometer readings");
  const imu::VectorObservation seen =
      imu::observe_W_from_A(acc / static_cast<double>(samples.size()), mag / static_cast<double>(with_field));
  if (!seen.ok()) {
    throw_precondition(field, std::string("no orientation from the still IMU's mean readings: ") +
                                  imu::observation_status_name(seen.status));
  }
  return seen.W_from_A;
}

CaptureCalibration calibrate_capture(const CalibrationCapture& capture, const CaptureCalibrationOptions& options) {
  const int poses = static_cast<int>(capture.poses.size());
  if (poses < options.min_poses) {
    throw_invalid("poses", std::to_string(poses) + " panel pose(s), need at least " +
                               std::to_string(options.min_poses) + " (eq. 8 is checked by the spread over poses)");
  }
  CaptureCalibration out;
  std::vector<std::array<Vec3, 4>> markers;
  std::vector<PanelInCamera> seen;
  std::vector<PanelImuReading> readings;
  for (int i = 0; i < poses; ++i) {
    const CapturePose& pose = capture.poses[static_cast<std::size_t>(i)];
    const std::string at = "poses[" + std::to_string(i) + "]";
    CapturePoseReport report;
    try {
      report.seen = panel_in_camera({capture.camera.width, capture.camera.height, pose.ir.data()},
                                    {capture.camera.width, capture.camera.height, pose.depth_mm.data()}, capture.camera,
                                    capture.panel, options.camera);
    } catch (const Error& error) {
      const std::string message = std::string(error.what()).substr(error.field().size() + 2);  // "field: message"
      throw Error(error.code(), at + "." + error.field(), message);
    }
    report.W_from_P = still_orientation(pose.panel_imu, at + ".panel_imu", options.min_imu_samples);
    report.W_from_B = still_orientation(pose.base_imu, at + ".base_imu", options.min_imu_samples);
    markers.push_back(pose.markers_E);
    seen.push_back(report.seen);
    readings.push_back({report.seen.pose.X_from_P, report.W_from_P, report.W_from_B});
    out.poses.push_back(report);
  }
  for (int i = 0; i < poses; ++i) {
    for (int j = i + 1; j < poses; ++j) {
      out.pose_spread_rad =
          std::max(out.pose_spread_rad, geometry::angle_between(readings[static_cast<std::size_t>(i)].K_from_P,
                                                                readings[static_cast<std::size_t>(j)].K_from_P));
    }
  }
  if (out.pose_spread_rad < options.min_pose_spread_rad) {
    throw_precondition("poses", "the panel turned at most " + std::to_string(out.pose_spread_rad * 180 / EIGEN_PI) +
                                    " degrees between poses (need " +
                                    std::to_string(options.min_pose_spread_rad * 180 / EIGEN_PI) +
                                    "): degenerate, IMU errors would not average out");
  }
  out.mocap = mocap_to_camera(markers, seen, capture.camera, capture.panel);
  out.base = base_imu_in_camera(readings);
  Eigen::Vector4d sum = Eigen::Vector4d::Zero();
  for (const PanelImuReading& r : readings)
    sum += geometry::to_wxyz(geometry::same_hemisphere(r.W_from_B, readings[0].W_from_B));
  out.K_from_W = K_from_W_from_base(out.base.K_from_B, geometry::from_wxyz(sum.normalized()));
  return out;
}

}  // namespace posefuse::calib
