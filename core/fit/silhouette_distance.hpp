#pragma once
// D_2D of paper 2 (II-D, Eq. 6-7): for every pixel, the closest silhouette pixel and its
// quasi-Euclidean distance (8-neighbour chamfer with steps 1 and sqrt(2)). Inside the silhouette
// the closest pixel is the pixel itself (distance 0).
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "fit/depth_frame.hpp"

namespace posefuse::fit {

struct SilhouetteDistanceMap {
  int width = 0;
  int height = 0;
  std::vector<float> distance_px;      // quasi-Euclidean distance to the silhouette
  std::vector<int32_t> closest_pixel;  // row-major index of the closest silhouette pixel
  // The pixels the two arrays hold (the whole image unless computed over a region); outside it
  // they hold infinity / -1.
  PixelRect region;
  // The region's silhouette pixels that have an 8-neighbour outside the silhouette or lie on the
  // region's edge (row-major indices, ascending): the only candidates for the closest silhouette
  // pixel of a point outside the region (a step towards the point from any other one is closer).
  std::vector<int32_t> border_pixels;

  // D_2D at image coordinates (u, v): the closest silhouette pixel's (col, row). Coordinates
  // outside the image are clamped to the border pixel first; outside `region` the closest pixel
  // is searched among border_pixels (first of equally close ones).
  Eigen::Vector2d closest(double u, double v) const;
};

// Quasi-Euclidean distance between pixels offset by (dx, dy): max + (sqrt(2) - 1) min.
float quasi_euclidean_distance(int dx, int dy);

// `silhouette[i] != 0` marks silhouette pixels. Throws posefuse::Error (field "silhouette") for
// a wrong size or an empty silhouette.
SilhouetteDistanceMap silhouette_distance_map(const std::vector<uint8_t>& silhouette, int width, int height);

// The same over the pixels of `region` only, from the silhouette pixels inside it: exact there
// for every pixel whose closest silhouette pixel lies in the region; pixels outside the region
// stay at infinity / -1. For tests that need only short distances (the zone sampling's edge
// band). Throws "region" for a region that is empty or leaves the image, "silhouette" as above
// (also when the region holds no silhouette pixel).
SilhouetteDistanceMap silhouette_distance_map(const std::vector<uint8_t>& silhouette, int width, int height,
                                              const PixelRect& region);

// D_2D for the fitter: the same closest pixels (up to ties) as silhouette_distance_map over the
// whole image, the chamfer run only over the silhouette's bounding box grown by margin_px (so that
// points near the silhouette are looked up) and points outside that searched among the border
// pixels. Errors as silhouette_distance_map.
SilhouetteDistanceMap silhouette_distance_map_near(const std::vector<uint8_t>& silhouette, int width, int height,
                                                   int margin_px = 16);
// The same into `map`, reusing its arrays when they have the image's size (only its previous
// region is cleared): the per-frame way, without full-image allocation or clearing.
void silhouette_distance_map_near(const std::vector<uint8_t>& silhouette, int width, int height,
                                  SilhouetteDistanceMap& map, int margin_px = 16);

// Silhouette of a frame: body index != kNoBody (depth is not required).
std::vector<uint8_t> silhouette_of(const DepthFrame& frame);
// The same into `silhouette` (resized to the frame, every value written).
void silhouette_of(const DepthFrame& frame, std::vector<uint8_t>& silhouette);

}  // namespace posefuse::fit
