#include "forearm/forearm_model.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "common/error.hpp"
#include "common/number_text.hpp"
#include "geometry/quaternion.hpp"
#include "geometry/rotation_mean.hpp"

namespace posefuse::forearm {

Quat F_from_A_calibration(const Quat& K_from_F_sdk, const Quat& K_from_W, const Quat& W_from_A) {
  return (K_from_F_sdk.conjugate() * K_from_W * W_from_A).normalized();  // eq. 9
}

Quat K_from_F_from_imu(const Quat& K_from_W, const Quat& W_from_A, const Quat& F_from_A) {
  return (K_from_W * W_from_A * F_from_A.conjugate()).normalized();  // eq. 11
}

Vec3 imu_position_from_strap(const Vec3& strap_K, const Vec3& elbow_K, const Vec3& wrist_K, const Quat& K_from_F,
                             double r_m) {
  if (!strap_K.allFinite()) throw_invalid("strap_K", "not finite");
  if (!elbow_K.allFinite()) throw_invalid("elbow_K", "not finite");
  if (!wrist_K.allFinite()) throw_invalid("wrist_K", "not finite");
  if (!K_from_F.coeffs().allFinite()) throw_invalid("K_from_F", "not finite");
  const Vec3 axis = wrist_K - elbow_K;
  const double length_sq = axis.squaredNorm();
  if (length_sq < 1e-8) throw_invalid("elbow_K/wrist_K", "elbow and wrist coincide");
  const double u = std::clamp((strap_K - elbow_K).dot(axis) / length_sq, 0.0, 1.0);
  const Vec3 origin_K = elbow_K + u * axis;
  return origin_K + K_from_F.normalized() * Vec3(r_m, 0.0, 0.0);  // eq. 10
}

namespace {

void check_frame(const CalibrationFrame& f, std::size_t i) {
  const std::string at = "frames[" + std::to_string(i) + "].";
  if (!f.shoulder_K.allFinite()) throw_invalid(at + "shoulder_K", "not finite");
  if (!f.elbow_K.allFinite()) throw_invalid(at + "elbow_K", "not finite");
  if (!f.wrist_K.allFinite()) throw_invalid(at + "wrist_K", "not finite");
  if (!f.strap_K.allFinite()) throw_invalid(at + "strap_K", "not finite");
  if (!f.K_from_F_sdk.coeffs().allFinite() || f.K_from_F_sdk.norm() < 0.5) {
    throw_invalid(at + "K_from_F_sdk", "not a finite quaternion");
  }
  if (!f.W_from_A.coeffs().allFinite() || f.W_from_A.norm() < 0.5) {
    throw_invalid(at + "W_from_A", "not a finite quaternion");
  }
  if ((f.wrist_K - f.elbow_K).norm() < 1e-4) throw_invalid(at + "wrist_K", "coincides with the elbow");
}

// d_sw over a still hold: the mean, unless the values form two groups more than
// kWristGroupGapM apart. A wrist measured in depth (forearm_axis_depth.hpp) is the hand's widening
// in some frames and the fingertips, 10-13 cm further, in others (seed 3's left arm on the body
// render: the mean came out 25 mm long); the fingertips lie beyond the wrist, never before it, so
// the nearer group is the wrist, if it holds at least kWristGroupMinFrames frames (fewer are too
// few to trust, and the farther group is used).
constexpr double kWristGroupGapM = 0.04;
constexpr std::size_t kWristGroupMinFrames = 3;

double hold_wrist_distance(std::vector<double> d) {
  std::sort(d.begin(), d.end());
  std::size_t split = 0;
  double widest = 0.0;
  for (std::size_t i = 1; i < d.size(); ++i) {
    if (d[i] - d[i - 1] > widest) {
      widest = d[i] - d[i - 1];
      split = i;
    }
  }
  const auto mean = [&](std::size_t from, std::size_t to) {
    return std::accumulate(d.begin() + static_cast<std::ptrdiff_t>(from), d.begin() + static_cast<std::ptrdiff_t>(to),
                           0.0) /
           static_cast<double>(to - from);
  };
  if (widest <= kWristGroupGapM) return mean(0, d.size());
  return split >= kWristGroupMinFrames ? mean(0, split) : mean(split, d.size());
}

}  // namespace

ForearmCalibration calibrate_forearm(const std::vector<CalibrationFrame>& frames, const Quat& K_from_W,
                                     const CalibrationOptions& options) {
  if (!K_from_W.coeffs().allFinite()) throw_invalid("K_from_W", "not finite");
  if (options.min_still_frames < 2 || !(options.still_radius_m > 0.0) || !(options.still_angle_rad > 0.0)) {
    throw_invalid("options", "min_still_frames must be >= 2, still_radius_m and still_angle_rad > 0");
  }
  for (std::size_t i = 0; i < frames.size(); ++i) {
    check_frame(frames[i], i);
    if (i > 0 && frames[i].t_us <= frames[i - 1].t_us) {
      throw_invalid("frames[" + std::to_string(i) + "].t_us", "not after the previous frame");
    }
  }
  // Longest run of frames whose arm IMU orientation and elbow and wrist stay near the run's
  // first frame's (a radius, not a frame-to-frame speed: joint noise makes per-frame speeds
  // unreliable). The wrist is held to the first frame's elbow -> wrist line, not its point: a
  // wrist measured in depth (forearm_axis_depth.hpp) moves along the forearm by ~11 cm between
  // frames where the hand's widening is seen and frames where the fingertips are taken, which
  // broke seed 3's left calibration hold into runs of at most 9 frames on the body render.
  const auto off_line = [](const Vec3& p, const Vec3& a, const Vec3& b) {
    const Vec3 axis = (b - a).normalized();
    const Vec3 d = p - a;
    return (d - d.dot(axis) * axis).norm();
  };
  std::size_t best_first = 0, best_count = 0;
  for (std::size_t first = 0; first < frames.size() && frames.size() - first > best_count; ++first) {
    const CalibrationFrame& f0 = frames[first];
    std::size_t end = first + 1;
    while (end < frames.size() &&
           geometry::angle_between(frames[end].W_from_A, f0.W_from_A) < options.still_angle_rad &&
           (frames[end].elbow_K - f0.elbow_K).norm() < options.still_radius_m &&
           off_line(frames[end].wrist_K, f0.elbow_K, f0.wrist_K) < options.still_radius_m) {
      ++end;
    }
    if (end - first > best_count) {
      best_first = first;
      best_count = end - first;
    }
  }
  if (best_count < static_cast<std::size_t>(options.min_still_frames)) {
    throw_precondition("frames", "the calibration pose is held still for " + std::to_string(best_count) +
                                     " frames; need " + std::to_string(options.min_still_frames));
  }

  ForearmCalibration out;
  out.first_frame = best_first;
  out.frame_count = best_count;
  std::vector<Quat> per_frame;
  std::vector<double> wrist_distances;
  const double n = static_cast<double>(best_count);
  for (std::size_t i = best_first; i < best_first + best_count; ++i) {
    const CalibrationFrame& f = frames[i];
    const Vec3 axis = (f.wrist_K - f.elbow_K).normalized();
    const double along = (f.strap_K - f.elbow_K).dot(axis);  // strap projected on the core line
    const Vec3 core_point = f.elbow_K + along * axis;
    out.model.r_m += (f.strap_K - core_point).norm() / n;
    out.model.d_se_m += along / n;
    wrist_distances.push_back((f.wrist_K - core_point).norm());
    out.model.d_ul_m += (f.elbow_K - f.shoulder_K).norm() / n;
    per_frame.push_back(F_from_A_calibration(f.K_from_F_sdk.normalized(), K_from_W, f.W_from_A.normalized()));
  }
  out.model.d_sw_m = hold_wrist_distance(std::move(wrist_distances));
  out.model.F_from_A = geometry::chordal_mean(per_frame);
  out.F_from_A_spread_rad = geometry::rms_angle_rad(per_frame, out.model.F_from_A);
  out.d_ul_uncertainty_m = std::sqrt(2.0 / 3.0) * options.camera_joint_error_m;
  const std::string hold = "the calibration hold of " + std::to_string(best_count) + " frames ";
  if (!(out.model.d_ul_m >= options.min_upper_arm_m && out.model.d_ul_m <= options.max_upper_arm_m)) {
    throw_precondition("frames", hold + "has an upper arm (shoulder to elbow) of " +
                                     fixed_text(100.0 * out.model.d_ul_m, 1) + " cm, outside " +
                                     fixed_text(100.0 * options.min_upper_arm_m, 0) + "-" +
                                     fixed_text(100.0 * options.max_upper_arm_m, 0) + " cm: not an arm in the pose");
  }
  if (!(out.F_from_A_spread_rad <= options.max_F_from_A_spread_rad)) {
    constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;
    throw_precondition("frames", hold + "gives mountings (eq. 9) spread " +
                                     fixed_text(out.F_from_A_spread_rad * kDegPerRad, 1) + " deg RMS, above " +
                                     fixed_text(options.max_F_from_A_spread_rad * kDegPerRad, 0) +
                                     ": the skeleton did not show one pose while the IMU was still");
  }
  return out;
}

}  // namespace posefuse::forearm
