#pragma once
// The calibration panel seen by the depth/IR camera (paper 1, II-F.1), frame K.
//
// 1. Bright points: the IR image is thresholded at bright_fraction of its maximum; connected
//    blobs of min..max_blob_pixels pixels give intensity-weighted centroids. Exactly four are
//    required: the markers.
// 2. Labels: the most collinear triple is the long leg; its middle point is M1; of its ends the
//    one nearer (in the image) to the fourth point M3 is the corner M0, the other M2.
// 3. Regions: an affine map from the panel plane (x, y in P) to the image, fitted to the four
//    marker pixels, sorts each depth pixel into the X strip, the Y strip and the board (minus
//    region_margin_m at the edges and marker_clearance x the marker radius around markers, so
//    that the map's perspective error cannot put a pixel off its region). The affine map
//    ignores perspective (~1 cm off at 1.6 m), so steps 3-5 run twice: first with the regions
//    from the affine map and the plane from the strips alone; then the bright points' rays are
//    intersected with that plane (raised by the marker height), the model markers fitted to
//    them (Kabsch), and the regions placed by that fit (exact), dropping points more than
//    5 x max_plane_rms_m off the plane.
// 4. PCA (geometry/point_pca.hpp) of the three 3D point groups: the X strip's first component is
//    x_P, the Y strip's is y_P, the board's third is z_P; signs towards M2, towards M3 and out
//    of the front face. The axes are made orthonormal (nearest rotation, SVD) and turned into
//    K_from_P by van Waveren's method.
// 5. Origin: the virtual intersection of the X and Y lines (each through its group's centroid),
//    i.e. the midpoint of their closest points.
// Residuals are reported; bad geometry is refused with a posefuse::Error naming it.
#include <array>
#include <cstdint>

#include "calib/panel.hpp"
#include "geometry/image_view.hpp"
#include "geometry/pinhole_camera.hpp"

namespace posefuse::calib {

using geometry::PinholeCamera;
using geometry::Vec2;

using geometry::IrImageView;
using DepthView = geometry::DepthImageView;  // the same pixels as the IR image (one sensor)

struct PanelCameraOptions {
  double bright_fraction = 0.6;  // of the image maximum
  int min_blob_pixels = 3;
  int max_blob_pixels = 2000;
  double region_margin_m = 0.012;
  double marker_clearance = 2.0;  // times marker_radius_m
  int min_group_points = 40;
  double min_strip_elongation = 4.0;  // sqrt(variance along / variance across) for a strip
  double max_plane_rms_m = 0.005;     // board points from their plane (Kinect noise at 1.6 m: ~3 mm)
  double max_axis_skew_rad = 0.05;    // |90 deg - angle(x, y)| and the like (2.9 degrees)
  double max_intersection_gap_m = 0.01;
  double max_marker_residual_px = 2.5;  // model markers reprojected vs the bright points (RMS)
};

struct PanelInCamera {
  PanelPose pose;                 // K_from_P and the origin in K
  std::array<Vec2, 4> marker_px;  // bright points M0..M3
  int x_points = 0, y_points = 0, board_points = 0;
  double x_elongation = 0.0, y_elongation = 0.0;
  double board_rms_m = 0.0;         // board points from their plane
  double axis_skew_rad = 0.0;       // largest deviation from orthogonality of x, y, z
  double intersection_gap_m = 0.0;  // between the X and Y lines
  double marker_residual_px = 0.0;  // RMS reprojection of the model markers
};

// Throws posefuse::Error: kInvalidArgument "ir.pixels" / "depth.pixels" (missing or size
// not the camera's), "camera.*" (bad intrinsics), "panel.*"; kFailedPrecondition "ir" (not four
// bright points), "ir.markers" (no L among them), "depth.x_strip" / "depth.y_strip" /
// "depth.board" (too few points, not a strip, not flat), "panel.axes" (skew), "panel.origin"
// (lines do not meet), "panel.markers" (reprojection residual): the calibration is refused.
PanelInCamera panel_in_camera(const IrImageView& ir, const DepthView& depth, const PinholeCamera& camera,
                              const PanelGeometry& panel, const PanelCameraOptions& options = {});

}  // namespace posefuse::calib
