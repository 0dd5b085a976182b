#pragma once
// A slow correction of the IMU's forearm orientation towards the forearm axis the depth camera
// sees (beyond paper 1, which uses eq. 11 as it is).
//
// Why: eq. 11's K_from_F = K_from_W W_from_A A_from_F carries the IMU filter's own error, and
// on the body render's protocol that is mostly its inclination (a tilt about a horizontal axis
// of W, docs/forearm.md "Orientation on the body render"): a rotation E of W that changes over
// seconds, i.e. a rotation K_from_W E K_from_W^-1 of K in front of every K_from_F. Each visible
// frame's depth-fitted elbow -> wrist segment (forearm_axis_depth.hpp) measures y_F, the forearm
// axis, in K: two of the three angles of that rotation, and over frames with the forearm in
// different directions all three.
//
// How: the correction C (a rotation of K, identity at first) is applied to every K_from_F. At
// each frame whose forearm passed the occlusion tests, the angle between C K_from_F y_F and the
// depth axis is measured; if it is below max_angle_rad (larger: the depth segment ran up the
// upper arm or onto the hand, measured 18-30 deg at worst) C is turned by gain times it about the
// axis perpendicular to both: a complementary filter whose time constant is about
// frame_period / gain (1.7 s at 30 frames/s and 0.02). The roll about the forearm (the
// calibration's, eq. 9) is not observable from the axis and is left as it is.
#include "forearm/forearm_types.hpp"

namespace posefuse::forearm {

struct VisualAxisCorrectionOptions {
  // Fraction of the angle taken out at each used frame. Replayed offline on ten protocol seeds
  // (docs/forearm.md): 0.02 best; larger gains let the depth axis's own errors through.
  double gain = 0.02;
  // Frames whose depth axis is further than this from the corrected IMU axis are not used.
  double max_angle_rad = 8.0 * 3.14159265358979323846 / 180.0;
};

class VisualAxisCorrection {
 public:
  // Throws posefuse::Error kInvalidArgument for a gain outside (0, 1] or a max angle outside
  // (0, pi/2].
  explicit VisualAxisCorrection(const VisualAxisCorrectionOptions& options = {});

  // The corrected orientation C * K_from_F.
  Quat apply(const Quat& K_from_F) const { return (K_correction_ * K_from_F).normalized(); }

  // One visible frame: the IMU's own K_from_F at the frame's time (eq. 11, not corrected), with
  // the correction as it is now, against the depth axis from elbow_K to wrist_K. (The samples
  // already emitted for that time used an older correction; measuring those would count the
  // steps since then twice.) Returns whether the frame was used: not when a point is not finite,
  // the segment is shorter than 5 cm or the angle is above max_angle_rad.
  bool observe(const Quat& K_from_F_imu, const Vec3& elbow_K, const Vec3& wrist_K);

  const Quat& K_correction() const { return K_correction_; }
  std::uint64_t frames_used() const { return frames_used_; }

 private:
  VisualAxisCorrectionOptions options_;
  Quat K_correction_ = Quat::Identity();
  std::uint64_t frames_used_ = 0;
};

}  // namespace posefuse::forearm
