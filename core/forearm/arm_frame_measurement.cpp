#include "forearm/arm_frame_measurement.hpp"

#include <optional>

#include "forearm/forearm_axis_depth.hpp"
#include "forearm/upper_arm_depth.hpp"

namespace posefuse::forearm {

namespace {

bool has_pixels(const auto& image) { return image.pixels != nullptr && image.width > 0 && image.height > 0; }

}  // namespace

void measure_arm_frame(ArmFrame& arm, const geometry::DepthImageView& depth, const geometry::PixelRays& depth_rays,
                       const ArmMeasurementOptions& options) {
  if (!arm.forearm_tracked || !has_pixels(depth)) return;
  if (options.axis_from_depth || options.upper_arm_from_depth) {
    std::optional<MeasuredUpperArm> upper_arm;
    if (options.axis_from_depth && arm.shoulder_tracked) {
      // Both limbs, so that the upper arm's points next to the elbow are not taken for the forearm's.
      if (const auto axes = measure_arm_axes(depth, depth_rays, arm.shoulder_K, arm.elbow_K, arm.wrist_K)) {
        arm.elbow_K = axes->forearm.elbow_K;
        arm.wrist_K = axes->forearm.wrist_K;
        arm.axis_from_depth = true;
        upper_arm = axes->upper_arm;
      }
    } else if (options.axis_from_depth) {
      if (const auto axis = measure_forearm_axis(depth, depth_rays, arm.elbow_K, arm.wrist_K)) {
        arm.elbow_K = axis->elbow_K;
        arm.wrist_K = axis->wrist_K;
        arm.axis_from_depth = true;
      }
    } else if (options.calibrating && arm.shoulder_tracked) {
      upper_arm = measure_upper_arm_axis(depth, depth_rays, arm.shoulder_K, arm.elbow_K, arm.wrist_K);
    }
    // Used by the calibration only (the arm plane's upper arm, forearm.upper_arm = depth).
    if (upper_arm && options.upper_arm_from_depth && options.calibrating) {
      arm.upper_arm_direction_K = upper_arm->direction_K;
    }
  }
}

void find_arm_strap(ArmFrame& arm, const geometry::DepthImageView& depth, const geometry::GrayImageView& gray,
                    const StrapCameras& cameras) {
  if (!arm.forearm_tracked || !has_pixels(depth) || !has_pixels(gray)) return;
  const StrapDetection strap = detect_strap(gray, depth, cameras, arm.elbow_K, arm.wrist_K);
  if (strap.found()) arm.strap_K = strap.strap_K;
}

std::size_t drop_straps_nearer_another_wrist(std::vector<ArmFrame>& arms) {
  std::vector<bool> drop(arms.size(), false);
  for (std::size_t i = 0; i < arms.size(); ++i) {
    const ArmFrame& own = arms[i];
    if (!own.strap_K || !own.forearm_tracked) continue;
    const double own_distance_m = (*own.strap_K - own.sdk_wrist_K).norm();
    for (std::size_t j = 0; j < arms.size(); ++j) {
      const ArmFrame& other = arms[j];
      if (j != i && other.forearm_tracked && (*own.strap_K - other.sdk_wrist_K).norm() < own_distance_m) drop[i] = true;
    }
  }
  std::size_t dropped = 0;
  for (std::size_t i = 0; i < arms.size(); ++i) {
    if (!drop[i]) continue;
    arms[i].strap_K.reset();
    ++dropped;
  }
  return dropped;
}

}  // namespace posefuse::forearm
