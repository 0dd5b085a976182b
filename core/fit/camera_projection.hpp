#pragma once
// Perspective projection Pi_< of paper 2 (eq. 6, 7) with its Jacobian, for the bg and bgJoint
// residuals. Same model as raycast::DepthCamera::project (pinhole with radial distortion, K has
// x left, y up, z forward), but without its field-of-view gate: the residuals need a smooth
// function for any point in front of the camera.
#include <Eigen/Core>

#include "raycast/depth_camera.hpp"

namespace posefuse::fit {

struct Projection {
  Eigen::Vector2d pixel;                        // image coordinates (u, v)
  Eigen::Matrix<double, 2, 3> d_pixel_d_point;  // d (u, v) / d p_K
};

// Requires p_K.z() > 0 (the caller skips points behind the camera).
Projection project_with_jacobian(const raycast::DepthIntrinsics& intrinsics, const Eigen::Vector3d& p_K);

}  // namespace posefuse::fit
