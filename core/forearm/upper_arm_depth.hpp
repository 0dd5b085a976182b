#pragma once
// The upper arm's direction measured in the depth image, for the calibration pose's roll.
//
// Paper 1 (II-H, eq. 9) fixes the forearm frame in the calibration pose (Fig. 3b: upper arm
// sideways, forearm up, both in the coronal plane, palm to the camera). y_F is the forearm axis;
// x_F, and so the roll of A_from_F about y_F, is the normal of the plane spanned by the upper arm
// and the forearm (forearm_orientation.hpp K_from_F_calibration_pose). Taking the upper arm from
// the SDK's shoulder puts the shoulder's 5-10 cm bias on a ~0.3 m upper arm into that roll, a
// constant error of 10-20 degrees in every later orientation. The wrist IMU's gravity cannot
// replace it: the forearm is vertical in the pose, so gravity lies along y_F and says nothing
// about the roll about it. The depth image sees the upper arm's surface, so:
//  1. Depth pixels within search_radius_m of the line from the SDK shoulder to the (measured)
//     elbow are candidates if their position along it is in [shoulder_skip_fraction, 1] (the
//     part next to the SDK shoulder is skipped: the torso is there, and the shoulder's bias is
//     largest relative to the arm there), at least elbow_clearance_m short of the elbow along it,
//     and more than forearm_clearance_m from the forearm axis (a forearm folded back over the
//     upper arm). The cut across the arm keeps the kept points symmetric about its axis.
//  2. A principal-axis line through them, refitted on the points within inlier_radius_m of it
//     (forearm_axis_depth.hpp fit_depth_line). A cylinder's visible half sampled along its
//     length has its centroid line parallel to the axis, so the line's direction is the upper
//     arm's; no radius or end is needed. The cuts of step 1 are then redone across the fitted
//     line and the line refitted.
//  3. The direction is the line through the centroids of 2 cm slices across it (the end slices
//     left out): a PCA of a piece cut across another direction leans towards it. Each slice's
//     centroid is moved (pi/4) R(s) away from the camera, R(s) a line fitted to the slices'
//     radii (their lateral spread, as in cylinder_axis), because an upper arm tapers towards the
//     elbow: the surface line of a cone leans towards the camera at its thick end
//     (taper_correction).
// Only the SDK shoulder's role as "where to look" remains; the direction does not follow its bias.
#include <optional>

#include "forearm/forearm_axis_depth.hpp"
#include "forearm/forearm_types.hpp"
#include "geometry/image_view.hpp"
#include "geometry/pixel_rays.hpp"

namespace posefuse::forearm {

struct UpperArmAxisOptions {
  double search_radius_m = 0.15;        // the SDK shoulder is 5-10 cm off, plus the arm's radius
  double shoulder_skip_fraction = 0.1;  // of the SDK shoulder -> elbow length
  double elbow_clearance_m = 0.07;      // along the arm from the elbow (the forearm's radius + margin)
  double forearm_clearance_m = 0.05;    // from the forearm's axis (its surface lies R = 3-4 cm from it)
  double inlier_radius_m = 0.07;        // around the fitted surface line
  int refinements = 2;
  int min_points = 30;
  double min_length_m = 0.08;  // extent of the inliers along the line
  double slice_m = 0.02;       // slices across the line for the direction (step 3)
  // Each slice's centroid moved onto the axis by the fitted radius profile (step 3), only where a
  // depth pixel's footprint at the arm is at most max_taper_pixel_m: at the strap tests' 11 mm
  // pixels the slices' radii are too noisy (a plain cylinder's roll went from < 1.5 to 2.8 deg).
  bool taper_correction = true;
  double max_taper_pixel_m = 0.008;
};

struct MeasuredUpperArm {
  Vec3 direction_K = Vec3::UnitX();  // unit, shoulder -> elbow
  Vec3 centroid_K = Vec3::Zero();    // of the inliers (on the surface, not the axis)
  Vec3 axis_point_K = Vec3::Zero();  // on the axis, level with the centroid (cylinder_axis)
  double radius_m = 0.0;
  int points = 0;  // inliers of the last fit
};

// depth_rays: the depth camera's pixel rays (geometry/pixel_rays.hpp); shoulder_K: the SDK's
// shoulder; elbow_K, wrist_K: the forearm axis (measured in depth,
// forearm_axis_depth.hpp). Throws posefuse::Error kInvalidArgument naming "depth.pixels",
// "shoulder_K", "elbow_K", "wrist_K" or "options" for unusable input. nullopt when the depth image
// does not show an upper arm there (too few points, too short).
std::optional<MeasuredUpperArm> measure_upper_arm_axis(const geometry::DepthImageView& depth,
                                                       const geometry::PixelRays& depth_rays, const Vec3& shoulder_K,
                                                       const Vec3& elbow_K, const Vec3& wrist_K,
                                                       const UpperArmAxisOptions& options = {});

// Both limbs of one arm, each without the other's points. The forearm fit alone
// (measure_forearm_axis) takes the upper arm's points next to the elbow for the forearm's
// (measured on the calibration pose: the direction 15-20 degrees off, the elbow 9-10 cm), so:
//  1. the forearm axis alone, and the upper arm beside the SDK's shoulder -> elbow
//     (measure_upper_arm_axis with the SDK's forearm for the clearance);
//  2. if the two are bent by more than min_bend_rad, the upper arm's points (within
//     forearm.excluded_radius_m of its surface line) are removed from the forearm's candidates
//     (a straight arm is one cylinder: nothing tells the limbs apart, so nothing is removed);
//  3. the forearm axis is fitted again (measure_forearm_axis);
//  4. the upper arm is fitted again with the measured forearm as the clearance;
//  5. after step 2 the forearm's inliers stop short of the elbow (its points near the upper arm
//     went with the upper arm's), so the elbow is put where the two axes pass closest (a hinge:
//     the limbs' axes meet at the elbow), if that lies within max_elbow_shift_m of the end seen.
// nullopt when the forearm is not found; upper_arm empty when the upper arm is not. Throws as
// the two functions do.
struct MeasuredArm {
  MeasuredForearmAxis forearm;
  std::optional<MeasuredUpperArm> upper_arm;
};
std::optional<MeasuredArm> measure_arm_axes(const geometry::DepthImageView& depth,
                                            const geometry::PixelRays& depth_rays, const Vec3& shoulder_K,
                                            const Vec3& elbow_K, const Vec3& wrist_K,
                                            const ForearmAxisOptions& forearm_options = {},
                                            const UpperArmAxisOptions& upper_arm_options = {},
                                            double min_bend_rad = 25.0 * 3.14159265358979323846 / 180.0,
                                            double max_elbow_shift_m = 0.1);

}  // namespace posefuse::forearm
