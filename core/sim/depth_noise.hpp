#pragma once
// Kinect v2-like depth sensor errors applied to a clean rendered depth image, and a simple room
// (floor plane, back wall) rendered analytically behind the person.
//
// The error model, applied per pixel in this order:
//  1. room: the clean body depth is composited with the room planes (nearest surface wins);
//  2. incidence: the surface normal comes from the clean depth's gradients (central
//     differences of back-projected points, one-sided next to depth edges). Two neighbours
//     are on one surface unless their depths differ by more than
//     max(edge_min_jump_m, z * tan(edge_slope_deg) / f): a surface tilted up to
//     edge_slope_deg against the ray still counts as continuous, so its incidence is
//     measured, and anything steeper is a depth edge. Pixels seen at
//     more than `max_incidence_deg` between the viewing ray and the normal return nothing, as
//     the time-of-flight signal of a grazing surface is too weak; so do pixels without a
//     normal (no same-surface neighbour along their row or column: one-pixel slivers and
//     surfaces steeper than edge_slope_deg);
//  3. flying pixels: a pixel next to a depth edge becomes, with `flying_pixel_probability`, a mix
//     t * z_here + (1 - t) * z_neighbour, t ~ U(0, 1), of its own depth and the farthest-off
//     4-neighbour's: the sensor's pixel integrates light from both surfaces;
//  4. axial noise: z += sigma(z) * N(0, 1), sigma(z) = axial_sigma_base_m
//     + axial_sigma_quadratic_per_m * (z - 0.4 m)^2 (the form of Nguyen et al. 2012, with
//     coefficients reduced for the v2 time-of-flight sensor: 2.2 mm at 1.5 m, 5.6 mm at 3 m);
//  5. range: depths outside [min_range_m, max_range_m] return nothing;
//  6. quantisation: rounded to whole millimetres (uint16, 0 = nothing).
// The body index map is made to disagree with the depth silhouette as the SDK's does: at each
// boundary pixel of the clean body mask a random shift in [-max_edge_shift_px,
// max_edge_shift_px] erodes (< 0) or dilates (> 0) the mask by that many pixels there; body
// pixels whose depth was dropped become kNoBody.
//
// Deterministic for (seed, frame_index): each frame draws from its own SimRng stream.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "raycast/depth_camera.hpp"

namespace posefuse::sim {

struct DepthNoiseOptions {
  double axial_sigma_base_m = 0.0015;
  double axial_sigma_quadratic_per_m = 0.0006;  // sigma gain per (z - 0.4 m)^2, 1/m
  double max_incidence_deg = 78.0;
  double edge_min_jump_m = 0.05;
  double edge_slope_deg = 87.0;  // must exceed max_incidence_deg
  double flying_pixel_probability = 0.5;
  double min_range_m = 0.5;
  double max_range_m = 4.5;
  int max_edge_shift_px = 2;  // body index boundary shift, pixels
};

// Throws posefuse::Error naming the field for a bad option.
void validate(const DepthNoiseOptions& options);

// Axial noise standard deviation at depth z (metres), item 4 above.
double axial_sigma_m(const DepthNoiseOptions& options, double z_m);

// An infinite plane n . p = offset_m in the camera frame K (n unit).
struct RoomPlane {
  Eigen::Vector3d normal_K = Eigen::Vector3d::UnitZ();
  double offset_m = 4.0;
};

// A floor `camera_height_m` below the camera (K's y is up, so the floor is y = -height) and a
// back wall facing the camera at z = `wall_distance_m`. The camera is assumed level.
std::vector<RoomPlane> simple_room(double camera_height_m, double wall_distance_m);

// Renders the planes (nearest hit along each pixel ray) into `depth_mm` (z in mm, 0 = none),
// keeping any existing nearer nonzero value: call it on a body render to composite the room.
void composite_room(const raycast::DepthCamera& camera, const std::vector<RoomPlane>& planes,
                    std::vector<uint16_t>& depth_mm);

// Angle (degrees) between each pixel's viewing ray and the surface normal estimated from the
// depth image's gradients; NaN where the depth or all neighbours are missing.
std::vector<float> incidence_angles_deg(const raycast::DepthCamera& camera, const std::vector<uint16_t>& depth_mm,
                                        const DepthNoiseOptions& options);

struct NoisyDepth {
  std::vector<uint16_t> depth_mm;
  std::vector<uint8_t> body_index;
};

// The static room behind the person, rendered and its incidence measured once per session:
// composite() puts it behind a body render, and apply_depth_noise(..., &background) then
// recomputes the incidence only where the frame's depth or a 4-neighbour's differs from the
// room's (the person and its rim); elsewhere the cached value is the one the full computation
// would give, so the output is identical, only cheaper.
class StaticBackground {
 public:
  // Throws posefuse::Error naming the field for bad planes or options.
  StaticBackground(const raycast::DepthCamera& camera, const std::vector<RoomPlane>& planes,
                   const DepthNoiseOptions& options);

  // composite_room with the cached room depth: keeps nearer nonzero body pixels.
  void composite(std::vector<uint16_t>& depth_mm) const;

  const std::vector<uint16_t>& depth_mm() const { return depth_mm_; }
  const std::vector<float>& incidence_cosines() const { return incidence_cos_; }
  // Per pixel of the room, the depth (mm) of the neighbour it would fly towards, 0 for none.
  const std::vector<uint16_t>& flying_neighbour_mm() const { return flying_neighbour_mm_; }
  const DepthNoiseOptions& options() const { return options_; }

 private:
  std::vector<uint16_t> depth_mm_;
  std::vector<float> incidence_cos_;
  std::vector<uint16_t> flying_neighbour_mm_;
  DepthNoiseOptions options_;
};

// Applies the model to a clean depth (already composited with the room, if any) and its body
// index map (kNoBody where no person). Both sized width x height of the camera. `background`
// (optional, made with the same camera and options; kInvalidArgument otherwise): the room the
// depth was composited with, whose cached incidence is reused away from the person.
NoisyDepth apply_depth_noise(const raycast::DepthCamera& camera, const std::vector<uint16_t>& clean_depth_mm,
                             const std::vector<uint8_t>& clean_body_index, const DepthNoiseOptions& options,
                             std::uint64_t seed, std::int64_t frame_index,
                             const StaticBackground* background = nullptr);

}  // namespace posefuse::sim
