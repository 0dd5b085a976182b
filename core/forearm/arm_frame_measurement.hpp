#pragma once
// One arm in one camera frame measured in the images (paper 1, II-I; docs/forearm.md "Forearm
// axis from depth"): the SDK's joints only say where to look. The forearm axis (elbow and wrist)
// is replaced by the one fitted to the depth image, the upper arm's direction is measured for
// the calibration pose's arm plane, and the strap is searched for in the colour image.
#include <cstddef>
#include <vector>

#include "forearm/forearm_track.hpp"
#include "forearm/strap_detection.hpp"
#include "geometry/image_view.hpp"
#include "geometry/pixel_rays.hpp"

namespace posefuse::forearm {

struct ArmMeasurementOptions {
  bool axis_from_depth = true;       // forearm.axis = depth
  bool upper_arm_from_depth = true;  // forearm.upper_arm = depth
  // Before the arm's calibration: the upper arm's direction is kept for the arm plane.
  bool calibrating = true;
};

// Refines `arm`, whose SDK joints and tracking flags are set, in place: elbow_K, wrist_K and
// axis_from_depth from the depth image, upper_arm_direction_K (calibrating only). Only an arm
// whose forearm the SDK tracks is measured; an empty image is not used. depth_rays: the depth
// camera's pixel rays, built once per session (geometry/pixel_rays.hpp).
void measure_arm_frame(ArmFrame& arm, const geometry::DepthImageView& depth, const geometry::PixelRays& depth_rays,
                       const ArmMeasurementOptions& options);

// Then the strap: strap_K where detect_strap finds it along the measured forearm. Reads only the
// pixels of strap_profile_rect(cameras, arm.elbow_K, arm.wrist_K) in `gray`, so a colour frame
// decoded over the arms' rectangles alone will do (session/color_image.hpp). An arm whose forearm
// the SDK does not track, or an empty image: nothing.
void find_arm_strap(ArmFrame& arm, const geometry::DepthImageView& depth, const geometry::GrayImageView& gray,
                    const StrapCameras& cameras);

// Both arms' straps are alike dark bands just short of the wrist, and each arm's search runs
// along its own forearm axis, which with the hands together can run on over the other forearm (on
// the body render a right forearm axis 49 cm long, its search finding the left band 21 cm from
// the right IMU). Nearest-neighbour association on the SDK's wrists, which carry the same kind of
// error for both arms: a strap nearer another arm's wrist than its own (both forearms tracked in
// the frame) is taken to be that arm's and dropped from this one. Returns how many were dropped.
std::size_t drop_straps_nearer_another_wrist(std::vector<ArmFrame>& arms);

}  // namespace posefuse::forearm
