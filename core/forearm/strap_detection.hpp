#pragma once
// Strap detection in the RGB image (paper 1, II-I): the black strap band along the projected
// elbow -> wrist segment, mapped to the depth image and to 3D.
//
// 1. Elbow and wrist (K) are projected into the colour image (K -> colour by color_from_depth,
//    then the colour intrinsics); the grey levels along the segment between them are sampled
//    (bilinear, one sample per pixel of segment length, at least min_samples).
// 2. A moving average over window_fraction of the segment; its darkest position inside
//    [search_begin_fraction, search_end_fraction] is the strap. The band must be darker than
//    the profile's median by min_contrast grey levels and no brighter than max_strap_level,
//    otherwise the strap is not seen (skin, a sleeve or the background is not a strap). And it
//    must be a band across the forearm, not an edge: the windows side_offset_windows window
//    lengths before and after it (moved inwards at the profile's ends, but never onto the band's
//    window) must each be brighter than it by
//    min_side_contrast. On the body render the segment also crosses the sleeve at the elbow, the
//    hair behind the head, the trousers beyond a hanging hand: each is dark on one side only.
// 3. Colour pixel -> depth -> 3D (the job of the SDK's CoordinateMapper): the colour ray through
//    the strap pixel meets the elbow-wrist segment (closest point) near the strap; around that
//    point's depth pixel, every depth pixel whose 3D point projects within match_radius_px (at
//    least 0.75 depth pixels' footprint, so that one always can) of the strap pixel in the
//    colour image is a strap surface sample (the neighbourhood used is twice that radius).
//    Samples further than max_depth_spread_m from their median depth (edges, flying pixels) are
//    dropped; a least-squares plane through the rest, met by the colour ray, is the strap
//    point p_K on the surface facing the camera (the colour image fixes the position along the
//    forearm more finely than a 5-11 mm depth pixel).
// The IMU position then follows from eq. 10 (forearm_model.hpp imu_position_from_strap).
#include <cstdint>

#include "forearm/forearm_types.hpp"
#include "geometry/image_view.hpp"
#include "geometry/pinhole_camera.hpp"

namespace posefuse::forearm {

using geometry::PinholeCamera;
using geometry::Vec2;

using geometry::DepthImageView;
using geometry::GrayImageView;

// The two cameras of II-I: depth (frame K) and colour, p_color = color_from_depth * p_K.
struct StrapCameras {
  PinholeCamera depth;
  PinholeCamera color;
  Quat color_from_depth = Quat::Identity();
  Vec3 color_from_depth_m = Vec3::Zero();  // translation: K's origin in the colour frame
};

struct StrapDetectionOptions {
  int min_samples = 16;
  double window_fraction = 0.08;       // moving average length, fraction of the segment
  double search_begin_fraction = 0.1;  // elbow = 0, wrist = 1
  double search_end_fraction = 0.95;
  double min_contrast = 40.0;        // grey levels below the profile's median
  double max_strap_level = 100.0;    // grey level; a black strap is darker than this
  double side_offset_windows = 1.5;  // band centre to each side window's centre, in windows
  double min_side_contrast = 20.0;   // grey levels, each side window above the band
  double match_radius_px = 1.5;      // colour pixels
  int depth_search_radius_px = 8;    // depth pixels around the predicted strap pixel
  double max_depth_spread_m = 0.03;
  int min_depth_samples = 1;
};

enum class StrapMiss {
  kNone,
  kOutsideImage,  // elbow or wrist projects outside the colour image or behind the camera
  kNoDarkBand,    // no band dark enough along the segment: the strap is not seen
  kNoDepth,       // the band has no depth reading (hole, out of the depth image)
};
const char* strap_miss_name(StrapMiss miss);

struct StrapDetection {
  StrapMiss miss = StrapMiss::kNone;
  bool found() const { return miss == StrapMiss::kNone; }
  Vec2 color_px = Vec2::Zero();  // band centre in the colour image
  double fraction = 0.0;         // where along the projected segment (elbow 0, wrist 1)
  double band_level = 0.0;       // moving-average grey level at the band
  double contrast = 0.0;         // profile median - band_level
  double side_contrast = 0.0;    // the darker side window - band_level (0 when one is outside)
  Vec3 strap_K = Vec3::Zero();   // strap surface point in K (when found)
  int depth_samples = 0;
};

// Throws posefuse::Error kInvalidArgument naming the input for images without pixels or whose
// size disagrees with the cameras ("color.pixels", "depth.pixels"), non-finite joints
// ("elbow_K", "wrist_K"), or options out of range ("options"). A strap that is not seen is not
// an error: the result's miss says why.
StrapDetection detect_strap(const GrayImageView& color, const DepthImageView& depth, const StrapCameras& cameras,
                            const Vec3& elbow_K, const Vec3& wrist_K, const StrapDetectionOptions& options = {});

// The colour pixels detect_strap reads for this forearm (its grey profile along the projected
// elbow-wrist segment, bilinear), with a pixel to spare on every side, clipped to the image; an
// empty rectangle where the segment leaves the image (detect_strap's kOutsideImage). A colour image
// decoded over this rectangle alone gives detect_strap the result of the whole image.
geometry::PixelRect strap_profile_rect(const StrapCameras& cameras, const Vec3& elbow_K, const Vec3& wrist_K);

}  // namespace posefuse::forearm
