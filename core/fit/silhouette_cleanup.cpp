#include "fit/silhouette_cleanup.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
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
  uint8_t* body = frame.body_index.data();
  const uint16_t* depth = frame.depth_mm.data();
  for (std::size_t i = 0; i < n;) {
    if (i + 8 <= n && background_word(body + i)) {
      i += 8;
      continue;
    }
    for (const std::size_t end = std::min(n, i + 8); i < end; ++i) {
      if (body[i] == kNoBody || depth[i] == kNoDepth) continue;
      const double z_mm = depth[i];
      if (z_mm < near_mm || z_mm > far_mm) {
        body[i] = kNoBody;
        ++removed;
      }
    }
  }
  return removed;
}

}  // namespace posefuse::fit
