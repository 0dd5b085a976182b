#pragma once
// Least-squares ellipsoid fit for sensor calibration (paper 1, II-E-1, after Petrov's method,
// ref. [17]); shared by the magnetometer and the accelerometer calibration.
//
// The points are fitted with the general 9-coefficient quadric
//   A x^2 + B y^2 + C z^2 + 2D yz + 2E xz + 2F xy + 2G x + 2H y + 2I z = 1
// by linear least squares (normal equations, accumulated without storing the design matrix).
// To keep those well conditioned the points are first centred on their mean and scaled to unit
// RMS radius; results are mapped back to the input units. The quadric is then written as
// (x - o)^T S (x - o) = 1; it is an ellipsoid iff S is positive definite, with S = H diag(1/r^2)
// H^T giving the centre o, radii r = (alpha, beta, gamma) and axes H (a rotation, det +1).
#include <cstddef>
#include <vector>

#include "geometry/quaternion.hpp"
#include "geometry/rotation_matrix.hpp"

namespace posefuse::imu {

using geometry::Mat3;
using geometry::Vec3;

struct EllipsoidFit {
  Vec3 center = Vec3::Zero();    // o
  Vec3 radii = Vec3::Ones();     // alpha, beta, gamma: semi-axis lengths along axes' columns
  Mat3 axes = Mat3::Identity();  // H: columns are the unit semi-axis directions, det +1
  // sqrt(largest / smallest eigenvalue) of D^T D for the normalised design matrix D: how well
  // the points pin down the 9 coefficients. Measured for points spread over a cap of the
  // sphere: whole sphere 3-7 (36 or more points), hemisphere ~12, 60 degree cap ~30, 45 degree
  // cap ~60, 25 degree cap ~200; points in a plane: infinite. Nine points are often much worse
  // than more points over the same cap (up to ~7000 for 9 random directions).
  double condition_number = 0.0;

  // Eq. 3's matrix scaled to a sphere of `radius`: radius * H diag(1/alpha, 1/beta, 1/gamma) H^T.
  // It maps (x - center) of a point on the ellipsoid onto the sphere of that radius.
  Mat3 sphere_from_ellipsoid(double radius) const;
};

// Fits an ellipsoid to `points`. `field` names the input in errors. Throws posefuse::Error:
//  kFailedPrecondition (field) if there are fewer than 9 points, if condition_number exceeds
//  `max_condition_number` (the points do not determine the 9 coefficients: too few, planar or
//  clustered directions), or if the fitted quadric is not an ellipsoid (not positive definite);
//  kInvalidArgument (field[i]) on a non-finite point.
EllipsoidFit fit_ellipsoid(const std::vector<Vec3>& points, const char* field, double max_condition_number);

// Spread of |transform(p)| over the points as std/mean (0 for points on one sphere around 0).
// `linear` and `offset` give transform(p) = linear * (p - offset).
double relative_norm_spread(const std::vector<Vec3>& points, const Mat3& linear, const Vec3& offset);

}  // namespace posefuse::imu
