#include "calib/panel.hpp"

#include <cmath>
#include <string>

#include <Eigen/SVD>

#include "common/error.hpp"
#include "geometry/rotation_matrix.hpp"

namespace posefuse::calib {

std::array<Vec3, 4> PanelGeometry::markers_P() const {
  const double h = marker_height_m;
  return {Vec3(0, 0, h), Vec3(mid_marker_m, 0, h), Vec3(long_leg_m, 0, h), Vec3(0, short_leg_m, h)};
}

void validate(const PanelGeometry& p) {
  const auto finite_positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!finite_positive(p.long_leg_m) || !finite_positive(p.short_leg_m)) {
    throw_invalid("panel.long_leg_m", "legs must be positive");
  }
  if (!(p.mid_marker_m > 0.0 && p.mid_marker_m < p.long_leg_m)) {
    throw_invalid("panel.mid_marker_m", "M1 must lie between M0 and M2");
  }
  if (!finite_positive(p.marker_radius_m) || !(p.marker_height_m >= 0.0)) {
    throw_invalid("panel.marker_radius_m", "marker radius must be positive and height non-negative");
  }
  if (!finite_positive(p.strip_half_width_m) || p.strip_half_width_m * 4 > p.short_leg_m) {
    throw_invalid("panel.strip_half_width_m", "strips must be positive and much narrower than the legs");
  }
  if (!(p.board_x_min_m < 0.0 && p.board_x_max_m > p.long_leg_m && p.board_y_min_m < 0.0 &&
        p.board_y_max_m > p.short_leg_m)) {
    throw_invalid("panel.board_x_min_m", "the board must contain the markers");
  }
}

PanelPose panel_pose_from_markers(const std::array<Vec3, 4>& markers_E, const PanelGeometry& panel,
                                  double* rms_residual_m, double max_residual_m) {
  validate(panel);
  for (std::size_t i = 0; i < markers_E.size(); ++i) {
    if (!markers_E[i].allFinite()) throw_invalid("markers_E[" + std::to_string(i) + "]", "not finite");
  }
  const std::array<Vec3, 4> model = panel.markers_P();
  Vec3 mean_model = Vec3::Zero(), mean_measured = Vec3::Zero();
  for (std::size_t i = 0; i < 4; ++i) {
    mean_model += model[i] / 4.0;
    mean_measured += markers_E[i] / 4.0;
  }
  Eigen::Matrix3d cross = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < 4; ++i) cross += (markers_E[i] - mean_measured) * (model[i] - mean_model).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cross, Eigen::ComputeFullU | Eigen::ComputeFullV);
  // The markers span a plane: two singular values must be well above zero.
  if (svd.singularValues()(1) < 1e-6) throw_invalid("markers_E", "the markers are collinear or coincide");
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;  // no reflection
  const Eigen::Matrix3d E_from_P = svd.matrixU() * d * svd.matrixV().transpose();
  PanelPose pose;
  pose.X_from_P = geometry::quat_from_rotation_matrix(E_from_P);
  pose.origin_X = mean_measured - E_from_P * mean_model;
  double sum_sq = 0.0;
  for (std::size_t i = 0; i < 4; ++i) sum_sq += (pose.to_X(model[i]) - markers_E[i]).squaredNorm();
  const double rms = std::sqrt(sum_sq / 4.0);
  if (rms_residual_m) *rms_residual_m = rms;
  if (!(rms <= max_residual_m)) {
    throw_precondition("markers_E", "the markers fit the panel's L with an RMS residual of " +
                                        std::to_string(rms * 1e3) + " mm (limit " +
                                        std::to_string(max_residual_m * 1e3) +
                                        " mm): mislabelled markers or another panel");
  }
  return pose;
}

}  // namespace posefuse::calib
