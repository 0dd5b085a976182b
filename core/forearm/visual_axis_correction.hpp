#pragma once
// A slow correction of the IMU's forearm orientation towards the forearm axis the depth camera
// sees (beyond paper 1, which uses eq. 11 as it is).
//
// Why: eq. 11's K_from_F = K_from_W W_from_A A_from_F carries two errors that tilt the forearm
// axis (docs/forearm.md "Orientation on the body render"):
//  - the IMU filter's own, mostly its inclination: a rotation of W that changes over seconds, so
//    a rotation of K in front of every K_from_F (the K side);
//  - the mounting's, eq. 9's A_from_F from one calibration hold: a rotation of F behind it (the
//    F side).
// Each visible frame's depth-fitted elbow -> wrist segment (forearm_axis_depth.hpp) measures y_F,
// the forearm axis, in K: two angles per frame; over frames with the forearm in different
// directions both rotations, except the roll about y_F on the F side, which no axis shows.
//
// How: the correction K_side * K_from_F * F_side (identity at first) is applied to every
// K_from_F. At each frame whose forearm passed the occlusion tests, the angle between the
// corrected axis and the depth axis is measured; if it is below max_angle_rad (larger: the depth
// segment ran up the upper arm or onto the hand, measured 18-30 deg at worst) the corrected axis
// is turned towards the depth axis by gain_K times the angle through K_side and by gain_F times
// it through F_side (about the same axis, mapped into F, so perpendicular to y_F: the roll stays
// as calibrated). A complementary filter; at 30 frames/s and the default gains the time constant
// is about 1.7 s of VISUAL frames per side.
#include "forearm/forearm_types.hpp"

namespace posefuse::forearm {

struct VisualAxisCorrectionOptions {
  // Fractions of the angle taken out at each used frame, through the K side (the IMU filter's
  // error) and the F side (the mounting's). In the forearm stage on ten protocol seeds
  // (docs/forearm.md): gain_K 0.01 / 0.02 / 0.04 alone gave 4.03 / 4.01 / 4.06 deg pooled;
  // with gain_K 0.02, gain_F 0.005 / 0.02 / 0.04 / 0.08 gave 3.91 / 3.81 / 3.83 / 3.94 deg.
  double gain_K = 0.02;
  double gain_F = 0.02;
  // Frames whose depth axis is further than this from the corrected IMU axis are not used.
  double max_angle_rad = 8.0 * 3.14159265358979323846 / 180.0;
};

// The correction as it stands: K_from_F is corrected to K_side * K_from_F * F_side. K_from_A,
// the IMU's own orientation, takes only the K side.
struct AxisCorrection {
  Quat K_side = Quat::Identity();
  Quat F_side = Quat::Identity();
  Quat K_from_F(const Quat& K_from_F_imu) const { return (K_side * K_from_F_imu * F_side).normalized(); }
  Quat K_from_A(const Quat& K_from_A_imu) const { return (K_side * K_from_A_imu).normalized(); }
};

class VisualAxisCorrection {
 public:
  // Throws posefuse::Error kInvalidArgument for a gain outside [0, 1], gains that sum to 0 or
  // more than 1, or a max angle outside (0, pi/2].
  explicit VisualAxisCorrection(const VisualAxisCorrectionOptions& options = {});

  const AxisCorrection& correction() const { return correction_; }

  // One visible frame: the IMU's own K_from_F at the frame's time (eq. 11, not corrected), with
  // the correction as it is now, against the depth axis from elbow_K to wrist_K. (The samples
  // already emitted for that time used an older correction; measuring those would count the
  // steps since then twice.) Returns whether the frame was used: not when a point is not finite,
  // the segment is shorter than 5 cm or the angle is above max_angle_rad.
  bool observe(const Quat& K_from_F_imu, const Vec3& elbow_K, const Vec3& wrist_K);

  std::uint64_t frames_used() const { return frames_used_; }

 private:
  VisualAxisCorrectionOptions options_;
  AxisCorrection correction_;
  std::uint64_t frames_used_ = 0;
};

}  // namespace posefuse::forearm
