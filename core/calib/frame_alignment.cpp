#include "calib/frame_alignment.hpp"

#include <cmath>
#include <string>

#include "common/error.hpp"
#include "geometry/rotation_mean.hpp"

namespace posefuse::calib {

namespace {

double reprojection_rms_px(const MocapToCamera& m, const std::array<Vec3, 4>& markers_E, const PanelInCamera& seen,
                           const PinholeCamera& camera) {
  double sum_sq = 0.0;
  for (std::size_t i = 0; i < 4; ++i) {
    const auto px = geometry::project(camera, m.to_K(markers_E[i]));
    sum_sq += px ? (*px - seen.marker_px[i]).squaredNorm() : 1e12;
  }
  return std::sqrt(sum_sq / 4.0);
}

void check_unit(const Quat& q, const std::string& field) {
  if (!q.coeffs().allFinite() || std::abs(q.norm() - 1.0) > 1e-3) throw_invalid(field, "not a unit quaternion");
}

}  // namespace

MocapToCamera mocap_to_camera(const std::array<Vec3, 4>& markers_E, const PanelInCamera& seen,
                              const PinholeCamera& camera, const PanelGeometry& panel, double max_residual_px) {
  const PanelPose in_E = panel_pose_from_markers(markers_E, panel);
  MocapToCamera out;
  out.K_from_E = (seen.pose.X_from_P * in_E.X_from_P.conjugate()).normalized();  // eq. 4
  out.E_origin_K = seen.pose.origin_X - out.K_from_E * in_E.origin_X;            // eq. 5
  out.poses = 1;
  out.marker_residual_px = reprojection_rms_px(out, markers_E, seen, camera);
  if (!(out.marker_residual_px <= max_residual_px)) {
    throw_precondition("mocap.markers",
                       "mocap markers mapped into the camera land " + std::to_string(out.marker_residual_px) +
                           " px RMS from the IR points (limit " + std::to_string(max_residual_px) + ")");
  }
  return out;
}

MocapToCamera mocap_to_camera(const std::vector<std::array<Vec3, 4>>& markers_E, const std::vector<PanelInCamera>& seen,
                              const PinholeCamera& camera, const PanelGeometry& panel, double max_spread_rad,
                              double max_spread_m) {
  if (markers_E.empty() || markers_E.size() != seen.size()) {
    throw_invalid("poses", std::to_string(markers_E.size()) + " mocap readings for " + std::to_string(seen.size()) +
                               " camera readings; need the same number, at least one");
  }
  std::vector<MocapToCamera> single;
  std::vector<Quat> rotations;
  Vec3 origin_sum = Vec3::Zero();
  for (std::size_t i = 0; i < seen.size(); ++i) {
    single.push_back(mocap_to_camera(markers_E[i], seen[i], camera, panel, INFINITY));
    rotations.push_back(single.back().K_from_E);
    origin_sum += single.back().E_origin_K;
  }
  MocapToCamera out;
  out.K_from_E = geometry::chordal_mean(rotations);
  out.E_origin_K = origin_sum / static_cast<double>(seen.size());
  out.poses = static_cast<int>(seen.size());
  double origin_spread_sq = 0.0, residual_sq = 0.0;
  for (std::size_t i = 0; i < seen.size(); ++i) {
    origin_spread_sq += (single[i].E_origin_K - out.E_origin_K).squaredNorm() / static_cast<double>(seen.size());
    residual_sq +=
        std::pow(reprojection_rms_px(out, markers_E[i], seen[i], camera), 2) / static_cast<double>(seen.size());
  }
  out.marker_residual_px = std::sqrt(residual_sq);
  const double rotation_spread = geometry::rms_angle_rad(rotations, out.K_from_E);
  if (rotation_spread > max_spread_rad || std::sqrt(origin_spread_sq) > max_spread_m) {
    throw_precondition("mocap.poses", "the panel poses disagree: " + std::to_string(rotation_spread * 180 / EIGEN_PI) +
                                          " degrees and " + std::to_string(std::sqrt(origin_spread_sq) * 1e3) +
                                          " mm RMS between single-pose results");
  }
  return out;
}

BaseImuAlignment base_imu_in_camera(const std::vector<PanelImuReading>& readings, double max_spread_rad) {
  if (readings.empty()) throw_invalid("readings", "no panel readings");
  std::vector<Quat> per_reading;
  for (std::size_t i = 0; i < readings.size(); ++i) {
    const std::string at = "readings[" + std::to_string(i) + "].";
    check_unit(readings[i].K_from_P, at + "K_from_P");
    check_unit(readings[i].W_from_P, at + "W_from_P");
    check_unit(readings[i].W_from_B, at + "W_from_B");
    per_reading.push_back(
        (readings[i].K_from_P * readings[i].W_from_P.conjugate() * readings[i].W_from_B).normalized());  // eq. 8
  }
  BaseImuAlignment out;
  out.K_from_B = geometry::chordal_mean(per_reading);
  out.spread_rad = geometry::rms_angle_rad(per_reading, out.K_from_B);
  out.readings = static_cast<int>(readings.size());
  if (out.spread_rad > max_spread_rad) {
    throw_precondition("readings", "the eq. 8 results spread " + std::to_string(out.spread_rad * 180 / EIGEN_PI) +
                                       " degrees RMS (limit " + std::to_string(max_spread_rad * 180 / EIGEN_PI) +
                                       "): IMU slipped on the panel or a magnetic disturbance");
  }
  return out;
}

Quat K_from_W_from_base(const Quat& K_from_B, const Quat& W_from_B) {
  return (K_from_B * W_from_B.conjugate()).normalized();  // eq. 7
}

}  // namespace posefuse::calib
