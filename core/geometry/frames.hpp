#pragma once
// Fixed rotations between the world conventions we meet.
//
// W (paper 1, II-B): x magnetic north, y magnetic west, z up.
// ENU (e.g. the BROAD dataset): x east, y magnetic north, z up.
// W's north axis is ENU's y and W's west axis is ENU's -x: a +90 degree turn about z.
#include "geometry/quaternion.hpp"

namespace posefuse::geometry {

inline Quat ENU_from_W() { return Quat(Eigen::AngleAxisd(EIGEN_PI / 2.0, Vec3::UnitZ())); }
inline Quat W_from_ENU() { return ENU_from_W().conjugate(); }

}  // namespace posefuse::geometry
