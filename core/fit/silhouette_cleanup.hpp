#pragma once
// Removes body-index pixels whose depth cannot belong to the person: the camera's body index map
// is not aligned exactly with its depth (a ring of 1-2 px around the person is marked as body
// while its depth is the wall behind; paper 2 does not mention it, the simulator reproduces it,
// core/sim/depth_noise.hpp). Without this the zone sampling draws wall points at 4 m into the data
// term and the fit fails (energy ~10^4 on the simulator's frames).
//
// Kept: silhouette pixels with a depth reading within [min z - margin, max z + margin] of the
// camera skeleton's usable joints (positions in K). Pixels outside become background (kNoBody).
#include <cstddef>

#include "fit/depth_frame.hpp"
#include "fit/tracked_skeleton.hpp"

namespace posefuse::fit {

struct SilhouetteCleanupOptions {
  // Beyond the skeleton's depth range: body thickness behind the joints (~0.15 m) plus the
  // skeleton's joint errors (~0.1 m).
  double depth_margin_m = 0.3;
};

// Returns the number of pixels removed. A skeleton without usable joints changes nothing.
std::size_t remove_off_body_depth(DepthFrame& frame, const TrackedSkeleton& skeleton,
                                  const SilhouetteCleanupOptions& options = {});

}  // namespace posefuse::fit
