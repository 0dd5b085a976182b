#pragma once
// Removes body-index pixels whose depth cannot belong to the person: the camera's body index map
// is not aligned exactly with its depth (a ring of 1-2 px around the person is marked as body
// while its depth is the wall behind; paper 2 does not mention it, the simulator reproduces it,
// core/sim/depth_noise.hpp), and the sensor's flying pixels at the person's edge read depths
// between the person and what lies behind. Without this the zone sampling, which draws a third
// of its samples near the edge, puts those points into the data term and the fit fails (energy
// ~10^4 on the simulator's frames with the wall at 4 m; with a wall 0.5 m behind the subject, 761
// of 1165 frames of a boxing clip lost, docs/benchmarks.md "A wall close behind the subject").
//
// Kept: silhouette pixels with a depth reading within [min z - margin, max z + margin] of the
// camera skeleton's usable joints (positions in K) and, for the outer ring (body pixels with a
// background pixel within 2 px, in the body index as given), a point within `margin` of a bone
// between usable joints (a capsule around each bone: the same margin, body thickness plus joint
// error, taken per bone instead of over the whole skeleton's depth). Pixels outside become
// background (kNoBody); pixels without depth stay as they are.
#include <cstddef>

#include "fit/depth_frame.hpp"
#include "fit/tracked_skeleton.hpp"
#include "raycast/depth_camera.hpp"

namespace posefuse::fit {

struct SilhouetteCleanupOptions {
  // Beyond the skeleton's depth range: body thickness behind the joints (~0.15 m) plus the
  // skeleton's joint errors (~0.1 m).
  double depth_margin_m = 0.3;
};

// Returns the number of pixels removed. A skeleton without usable joints changes nothing. Without
// the camera (or for a frame not of its size) only the depth range is tested.
std::size_t remove_off_body_depth(DepthFrame& frame, const TrackedSkeleton& skeleton,
                                  const SilhouetteCleanupOptions& options = {},
                                  const raycast::DepthCamera* camera = nullptr);

}  // namespace posefuse::fit
