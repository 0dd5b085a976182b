#pragma once
// The Kinect v2 depth camera at a quarter of its resolution (intrinsics scaled by 1/4), which
// keeps the rendering tests fast.
#include "raycast/depth_camera.hpp"

namespace posefuse::sim::testing {

inline raycast::DepthIntrinsics quarter_kinect_intrinsics() {
  raycast::DepthIntrinsics k;
  k.width = 128;
  k.height = 106;
  k.fx = k.fy = 365.0 / 4;
  k.cx = 64.0;
  k.cy = 53.0;
  return k;
}

inline raycast::DepthCamera small_camera() { return raycast::DepthCamera(quarter_kinect_intrinsics()); }

}  // namespace posefuse::sim::testing
