#pragma once
// The forearm's axis measured in the depth image, independent of the SDK's joint errors.
//
// Paper 1 takes the forearm axis from the SDK's elbow and wrist (II-H, II-J, eq. 10). A real
// skeleton SDK biases each arm joint by several centimetres, which turns the calibration frame
// by tens of degrees, rejects the strap at most frames (II-J) and moves the IMU position (eq. 10)
// with the bias. The depth image sees the forearm's surface without that bias, so:
//  1. Depth pixels around the projected SDK elbow-wrist segment are back-projected; those within
//     search_radius_m of the segment (extended by end_margin_m at both ends) are candidates.
//  2. A principal-axis (PCA) line fit through them; points further than inlier_radius_m from
//     that line are dropped and the line refitted (refinements times): a surface line.
//  3. The visible half of a cylinder of radius R, sampled evenly across the image, has its mean
//     (pi/4) R nearer the camera than the axis, and its lateral spread (perpendicular to the axis
//     and to the viewing ray) is uniform in [-R, R], variance R^2 / 3 (less h^2 / 12 for depth
//     pixels a footprint h apart). So R = sqrt(3 var + h^2 / 4), and the axis is the surface line
//     moved (pi/4) R away from the camera.
//  4. The extreme inliers along the axis, moved out by half a depth pixel's footprint (the last
//     pixel on the forearm lies on average that far inside its end), are the elbow and the
//     distal end of what was seen. The hand continues the forearm's cylinder, so that end is the
//     fingertips, not the wrist (on the body render 10-12 cm beyond it), and the wrist is found
//     in the width profile (wrist_from_width_profile below).
#include <optional>
#include <vector>

#include "forearm/forearm_types.hpp"
#include "geometry/image_view.hpp"
#include "geometry/pinhole_camera.hpp"
#include "geometry/pixel_rays.hpp"

namespace posefuse::forearm {

struct ForearmAxisOptions {
  double search_radius_m = 0.15;  // SDK joints are off by 5-10 cm plus the forearm's radius
  double end_margin_m = 0.15;     // along the segment, beyond the SDK elbow and wrist
  double inlier_radius_m = 0.06;  // around the fitted surface line
  int refinements = 2;
  int min_points = 30;
  double min_length_m = 0.08;  // elbow to wrist
  // Candidates within this of `excluded` (another limb's surface line, e.g. the upper arm's next
  // to the elbow) are not the forearm's: a cylinder's visible points lie within ~1.3 R of its
  // surface line.
  double excluded_radius_m = 0.06;
  // Wrist from the width profile (wrist_from_width_profile); false: the distal end of the inliers.
  bool wrist_from_width = true;
  double slice_m = 0.01;             // slices across the axis for the width profile
  double hand_min_m = 0.04;          // the wrist lies at least this far before the distal end
  double hand_max_m = 0.16;          // and at most this far (a hand with fingers, ~0.18 m)
  double width_tolerance_m = 0.001;  // slices within this of the narrowest count as the wrist's
  double hand_widening_m = 0.008;    // the hand beyond the wrist is at least this much wider somewhere
  // Only where a depth pixel's footprint at the forearm is at most this (Kinect v2: 6.8 mm at
  // 2.5 m); coarser images keep the distal end.
  double max_width_pixel_m = 0.008;
};

struct SurfaceLine {
  Vec3 point = Vec3::Zero();
  Vec3 direction = Vec3::UnitX();  // unit
};

struct MeasuredForearmAxis {
  Vec3 elbow_K = Vec3::Zero();  // on the axis, the elbow end of the seen forearm
  Vec3 wrist_K = Vec3::Zero();  // on the axis, the wrist end
  double radius_m = 0.0;        // R of the fitted cylinder
  int points = 0;               // inliers of the last fit
};

// Depth pixels back-projected into K that lie within radius_m of the segment a-b (the pieces
// below are shared with upper_arm_depth.hpp). depth_rays: the depth camera's pixel rays, built
// once per camera (geometry/pixel_rays.hpp). Throws posefuse::Error kInvalidArgument
// "depth.pixels" when the image is missing or not the camera's size.
std::vector<Vec3> depth_points_near_segment(const geometry::DepthImageView& depth,
                                            const geometry::PixelRays& depth_rays, const Vec3& a, const Vec3& b,
                                            double radius_m);

// A principal-axis line through `points`, refitted `refinements` times on the points within
// inlier_radius_m of it; `inliers` are the last fit's points. nullopt when fewer than min_points
// are left.
struct DepthLine {
  Vec3 centroid = Vec3::Zero();
  Vec3 direction = Vec3::UnitX();  // unit, sign arbitrary
  std::vector<Vec3> inliers;
};
std::optional<DepthLine> fit_depth_line(std::vector<Vec3> points, double inlier_radius_m, int refinements,
                                        int min_points);

// Step 3 above for a fitted surface line: the cylinder's axis (point on it level with the
// line's centroid, the line's direction), radius R and the inliers' extent along it (from the
// centroid). nullopt when the line lies along the viewing ray (no width is seen).
struct CylinderAxis {
  Vec3 point = Vec3::Zero();
  Vec3 direction = Vec3::UnitX();
  double radius_m = 0.0;
  double along_min = 0.0, along_max = 0.0;
};
std::optional<CylinderAxis> cylinder_axis(const DepthLine& line, double depth_fx);

// The wrist along a seen forearm with its hand: a forearm narrows from the elbow to the wrist,
// and the hand beyond is at least as wide as the wrist in every view (the palm is wider, seen
// edge-on it is about as thick as the wrist, but then the fingers' spread and the thumb widen it),
// so the wrist is the narrow part between the two. `along` and `lateral` are the inliers'
// coordinates along the axis (elbow -> distal end) and across it (perpendicular to the axis and
// the viewing ray). The visible width of each slice_m slice is sqrt(12 var(lateral)) (a
// uniform spread across the width, less quantised than the extreme pixels), smoothed over three
// slices; among the slices from hand_max_m to hand_min_m before the distal end, those within
// width_tolerance_m of the narrowest are the wrist's narrow part, and its distal edge (the
// last such slice from the elbow) is the wrist: the hand begins there. Some slice beyond it must
// be hand_widening_m wider, else no hand is seen (a bare forearm, a hand end-on or cut off).
// Returns the position along the axis, or nullopt when too few slices are seen or no hand.
std::optional<double> wrist_from_width_profile(const std::vector<double>& along, const std::vector<double>& lateral,
                                               double along_max, const ForearmAxisOptions& options);

// depth_rays: the depth camera's pixel rays (geometry/pixel_rays.hpp).
// Throws posefuse::Error kInvalidArgument naming "depth.pixels", "elbow_K", "wrist_K" or
// "options" for unusable input. nullopt when the depth image does not show a forearm there
// (too few points, too short).
std::optional<MeasuredForearmAxis> measure_forearm_axis(const geometry::DepthImageView& depth,
                                                        const geometry::PixelRays& depth_rays, const Vec3& elbow_K,
                                                        const Vec3& wrist_K, const ForearmAxisOptions& options = {},
                                                        const std::optional<SurfaceLine>& excluded = std::nullopt);

}  // namespace posefuse::forearm
