#pragma once
// How bent the camera skeleton shows a limb, against what its joint errors alone can bend a
// straight one; and which legs a frame's fit therefore holds straight (docs/fitting.md, "Legs").
//
// Paper 2 fits 40 DOF, the body from the hips up, and holds the knees straight. The tracker keeps
// full-body poses (48 DOF: knees and ankles, 2 each, added) so that a fit can follow bent legs; a
// leg the camera does not show bent keeps its knee and ankle at zero, as in the 40-DOF fit,
// because left free on straight legs the fit bends them by a few degrees that the depth cannot
// tell from a lean of the trunk.
#include <Eigen/Core>
#include <vector>

#include "body/pose_parameters.hpp"
#include "fit/tracked_skeleton.hpp"

namespace posefuse::fit {

// The camera's joint error taken as the bound of a joint's displacement across its limb: the low
// end of the mean errors of Kinect v2 arm joints, 50-101 mm (paper 2's introduction, citing Wang
// et al. 2015).
inline constexpr double kCameraJointErrorM = 0.05;

// The angle between the segments a -> b and b -> c, degrees: 0 for a straight limb.
double limb_bend_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c);

// The bend a straight limb a - b - c shows when its middle joint lies offset_m off the line of
// its ends: atan(d / |b - a|) + atan(d / |c - b|), degrees (d = 5 cm: about 14 deg on an adult
// leg, 21 on an arm).
double bend_from_offset_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                            double offset_m);

struct BentLegs {
  bool left = false, right = false;
};

// A leg is bent when the camera tracks its hip, knee and ankle (inferred joints are the camera's
// guesses) and the knee bends more than the camera's errors can bend a straight leg: each of the
// three joints off by up to joint_error_m across the leg puts the knee up to twice that off the
// hip - ankle line, bend_from_offset_deg(2 e), about 27 deg on an adult leg for e = 5 cm. No
// skeleton: neither.
BentLegs camera_bent_legs(const TrackedSkeleton* skeleton, double joint_error_m = kCameraJointErrorM);

// The knee and ankle DOFs of `layout` (ascending) of the legs that are not bent: the ones a fit
// holds at zero. Empty for a layout without them (upper_body).
std::vector<int> held_leg_dofs(const body::PoseLayout& layout, BentLegs bent);

}  // namespace posefuse::fit
