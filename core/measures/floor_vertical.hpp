#pragma once
// The upward vertical in the camera frame K measured from the floor that a depth frame shows
// around the person (docs/measures.md, "The vertical"): the thorax angles are read against it
// when no calibrated IMU gives the world's orientation, instead of assuming a level camera.
//
// A floor is the largest plane among the background's depth pixels that faces up and lies below
// the camera:
//  1. Every `pixel_step`-th background pixel (no body, a depth reading) is back-projected; its
//     surface normal comes from the neighbours `pixel_step` to the right and below. Points whose
//     normal, turned to face the camera, is nearer K's y than K's x or z (within 45 degrees of
//     up, the nearest axis: a camera on a stand is closer to upright than to lying on its side)
//     are floor candidates; walls and the person's surroundings drop out.
//  2. RANSAC over the candidates: planes through three of them, whose normal is again within 45
//     degrees of K's y and which pass below the camera, scored by the candidates within
//     `inlier_distance_m`; the best is refitted to its inliers (point_pca).
//  3. Its spread: the floor is split in halves twice (at the median column: left and right; at
//     the median depth: near and far) and each half refitted; the RMS of the four halves' angles
//     to the whole floor's normal is the vertical's 1-sigma error. A floor that is flat and seen
//     well gives a fraction of a degree; one that bends (lens distortion, multipath near the
//     wall, a rug) or a small patch gives more, and the thorax angles' confidence follows it.
// None when fewer than `min_points` candidates lie on the best plane (no floor in view).
#include <cstdint>
#include <optional>
#include <vector>

#include "geometry/pinhole_camera.hpp"
#include "geometry/quaternion.hpp"

namespace posefuse::measures {

struct FloorVerticalOptions {
  int pixel_step = 4;               // every 4th pixel in each direction: ~13,000 of 512 x 424
  double inlier_distance_m = 0.03;  // 3 sigma of Kinect v2 depth noise at its 4.5 m range
  int min_points = 200;             // sampled pixels on the floor: ~3,200 image pixels, 1.5 %
  int iterations = 200;             // RANSAC draws (candidates are mostly floor after step 1)
  std::uint32_t seed = 1;           // the draws are deterministic for a frame
};

struct FloorVertical {
  geometry::Vec3 up_K = geometry::Vec3::UnitY();  // unit, against gravity
  double spread_rad = 0.0;                        // 1-sigma error of up_K (the halves' RMS angle)
  double camera_height_m = 0.0;                   // the camera's distance above the plane
  int points = 0;                                 // sampled pixels on the floor
};

// `depth_mm` and `body_index` are row-major images of the camera's size (0 = no depth; body index
// 255 = background, anything else is a person). Only the sampled pixels are back-projected, so a
// search holds no per-pixel table. Throws posefuse::Error kInvalidArgument ("camera",
// "depth_mm", "body_index", "floor_vertical_options.*") for a camera that geometry::validate
// refuses, sizes that do not match or bad options.
std::optional<FloorVertical> floor_vertical(const std::vector<std::uint16_t>& depth_mm,
                                            const std::vector<std::uint8_t>& body_index,
                                            const geometry::PinholeCamera& camera,
                                            const FloorVerticalOptions& options = {});

}  // namespace posefuse::measures
