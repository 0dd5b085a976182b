#include "fit/silhouette_cleanup.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace posefuse::fit {

std::size_t remove_off_body_depth(DepthFrame& frame, const TrackedSkeleton& skeleton,
                                  const SilhouetteCleanupOptions& options) {
  double min_z = std::numeric_limits<double>::infinity(), max_z = -min_z;
  for (int j = 0; j < kKinectJointCount; ++j) {
    if (!joint_unusable_reason(skeleton, j, /*accept_inferred=*/true).empty()) continue;
    const double z = skeleton.positions_K[static_cast<size_t>(j)].z();
    min_z = std::min(min_z, z);
    max_z = std::max(max_z, z);
  }
  if (!(min_z <= max_z)) return 0;
  const double near_mm = 1000.0 * (min_z - options.depth_margin_m), far_mm = 1000.0 * (max_z + options.depth_margin_m);
  std::size_t removed = 0;
  const std::size_t n = std::min(frame.depth_mm.size(), frame.body_index.size());
  for (std::size_t i = 0; i < n; ++i) {
    if (frame.body_index[i] == kNoBody || frame.depth_mm[i] == kNoDepth) continue;
    const double z_mm = frame.depth_mm[i];
    if (z_mm < near_mm || z_mm > far_mm) {
      frame.body_index[i] = kNoBody;
      ++removed;
    }
  }
  return removed;
}

}  // namespace posefuse::fit
