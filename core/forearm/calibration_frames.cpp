#include "forearm/calibration_frames.hpp"

#include "common/error.hpp"
#include "forearm/calibration_pose_check.hpp"
#include "forearm/forearm_orientation.hpp"

namespace posefuse::forearm {

CalibrationFrames select_calibration_frames(const std::vector<ArmFrame>& frames, std::int64_t window_end_us,
                                            const Vec3& up_K,
                                            const std::function<std::optional<Quat>(std::int64_t)>& W_from_A_at,
                                            const CalibrationFrameOptions& options) {
  CalibrationFrames out;
  // The arm plane's upper arm from depth when the depth showed it at enough frames to make a hold.
  for (const ArmFrame& f : frames) out.upper_arm_frames += f.t_us <= window_end_us && f.upper_arm_direction_K;
  out.depth_upper_arm =
      options.pose_orientation && options.upper_arm_from_depth && out.upper_arm_frames >= options.min_upper_arm_frames;
  for (const ArmFrame& f : frames) {
    if (f.t_us > window_end_us) break;
    if (!f.forearm_tracked || !f.shoulder_tracked) continue;
    if (!forearm_raised_for_calibration(f.elbow_K, f.wrist_K, up_K)) {
      ++out.not_raised;  // not the calibration pose (e.g. an arm resting at the side)
      continue;
    }
    if (!upper_arm_lowered_for_calibration(f.shoulder_K, f.elbow_K, up_K)) {
      ++out.overhead;
      continue;
    }
    if (!elbow_flexed_for_calibration(f.shoulder_K, f.elbow_K, f.wrist_K)) {
      ++out.straight;
      continue;
    }
    const std::optional<Quat> W_from_A = W_from_A_at(f.t_us);
    if (!W_from_A) continue;
    CalibrationFrame c;
    c.t_us = f.t_us;
    c.shoulder_K = f.shoulder_K;
    c.elbow_K = f.elbow_K;
    c.wrist_K = f.wrist_K;
    c.W_from_A = *W_from_A;
    if (options.pose_orientation) {
      try {
        Vec3 plane_shoulder_K = f.shoulder_K;
        if (out.depth_upper_arm) {
          if (!f.upper_arm_direction_K) continue;
          // Only the direction matters for the plane: the SDK shoulder moved onto the measured line.
          plane_shoulder_K = f.elbow_K - (f.shoulder_K - f.elbow_K).norm() * *f.upper_arm_direction_K;
        }
        c.K_from_F_sdk = K_from_F_calibration_pose(plane_shoulder_K, f.elbow_K, f.wrist_K);
      } catch (const Error&) {
        continue;  // a straight arm or one seen edge-on: not the calibration pose
      }
    } else {
      if (f.K_from_wrist_sdk.norm() < 0.5) continue;  // the SDK gave no orientation
      c.K_from_F_sdk = f.K_from_wrist_sdk.normalized();
    }
    // Without a strap the lengths are placeholders; only eq. 9 is used then.
    c.strap_K = f.strap_K.value_or(f.elbow_K + 0.8 * (f.wrist_K - f.elbow_K));
    out.without_strap.push_back(c);
    if (f.strap_K) out.with_strap.push_back(c);
  }
  return out;
}

}  // namespace posefuse::forearm
