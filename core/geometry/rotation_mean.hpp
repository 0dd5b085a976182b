#pragma once
// The mean of a set of rotations and their spread about it. The chordal mean (the normalised
// sum of hemisphere-aligned quaternions) is the rotation nearest all of them in the chordal
// metric; for the small spread of a held pose or repeated readings it equals the geodesic mean
// to well below their noise.
#include <vector>

#include "geometry/quaternion.hpp"

namespace posefuse::geometry {

// Chordal mean; `rotations` must not be empty.
Quat chordal_mean(const std::vector<Quat>& rotations);

// RMS of the angles (rad) between each rotation and `mean`; `rotations` must not be empty.
double rms_angle_rad(const std::vector<Quat>& rotations, const Quat& mean);

}  // namespace posefuse::geometry
