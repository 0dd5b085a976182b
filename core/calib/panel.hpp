#pragma once
// The calibration panel of paper 1 (II-F, Fig. 1b) and its pose from mocap markers.
//
// Frame P: origin at the corner of the L on the panel's front surface, x along the long leg,
// y along the short leg, z = x x y out of the front face (towards the cameras). Four reflective
// markers (spheres of marker_radius_m whose centres are marker_height_m above the surface):
//   M0 (0, 0) the corner, M1 (mid_marker_m, 0) and M2 (long_leg_m, 0) on the long leg,
//   M3 (0, short_leg_m) on the short leg.
// The depth camera cannot read the markers (too reflective); it reads three non-reflective
// regions: the X strip |y| <= strip_half_width_m along the long leg, the Y strip |x| <=
// strip_half_width_m along the short leg (both minus discs around the markers), and the board
// itself (the plane group).
#include <array>

#include "geometry/quaternion.hpp"

namespace posefuse::calib {

using geometry::Quat;
using geometry::Vec3;

struct PanelGeometry {
  double long_leg_m = 0.40;
  double mid_marker_m = 0.25;
  double short_leg_m = 0.25;
  double marker_radius_m = 0.012;
  double marker_height_m = 0.012;  // a sphere resting on the surface
  double strip_half_width_m = 0.02;
  // The board: x in [board_x_min_m, board_x_max_m], y in [board_y_min_m, board_y_max_m].
  double board_x_min_m = -0.06, board_x_max_m = 0.46;
  double board_y_min_m = -0.06, board_y_max_m = 0.31;

  std::array<Vec3, 4> markers_P() const;  // marker centres in P
};

// Throws posefuse::Error kInvalidArgument "panel.<field>" for a geometry that is not an L
// (legs not positive, M1 not between M0 and M2, markers off the board, strips wider than legs).
void validate(const PanelGeometry& panel);

// A panel (or any frame P) placed in a frame X: p_X = origin_X + X_from_P * p_P.
struct PanelPose {
  Quat X_from_P = Quat::Identity();
  Vec3 origin_X = Vec3::Zero();
  Vec3 to_X(const Vec3& p_P) const { return origin_X + X_from_P * p_P; }
};

// The panel's pose from its four marker centres measured by the mocap system (frame E), in
// M0..M3 order: the least-squares rigid fit (Kabsch; rotation -> quaternion by van Waveren) of
// markers_P() to them. `rms_residual_m` receives the RMS distance of the fitted markers from
// the measured ones. Throws posefuse::Error kInvalidArgument "markers_E[i]" for a non-finite
// marker, "markers_E" when they are (nearly) collinear or coincide, kFailedPrecondition
// "markers_E" when the residual exceeds max_residual_m (mislabelled markers, another panel).
PanelPose panel_pose_from_markers(const std::array<Vec3, 4>& markers_E, const PanelGeometry& panel,
                                  double* rms_residual_m = nullptr, double max_residual_m = 0.005);

}  // namespace posefuse::calib
