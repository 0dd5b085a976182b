#include "sim/scripted_motion.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "common/error.hpp"
#include "sim/option_checks.hpp"

namespace posefuse::sim {
namespace {

using std::numbers::pi;

Quat rotation(double angle, const Vec3& axis) { return Quat(Eigen::AngleAxisd(angle, axis)); }

void check_repetitions(int repetitions) {
  if (repetitions < 1 || repetitions > 10000) {
    throw_invalid("repetitions", "must be in 1..10000, got " + std::to_string(repetitions));
  }
}

// S_from_U0: the hanging arm's axes in S (x_U = -y_S, y_U = -z_S, z_U = x_S).
Quat S_from_hanging() {
  Eigen::Matrix3d m;
  m.col(0) = -Vec3::UnitY();
  m.col(1) = -Vec3::UnitZ();
  m.col(2) = Vec3::UnitX();
  return Quat(m);
}

}  // namespace

double smootherstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * x * (x * (6.0 * x - 15.0) + 10.0);
}

Quat S_from_upper_arm(const ArmAngles& a) {
  return rotation(-a.shoulder_abduction_rad, Vec3::UnitX()) * rotation(a.shoulder_flexion_rad, -Vec3::UnitY()) *
         S_from_hanging() * rotation(a.humeral_rotation_rad, Vec3::UnitY());
}

Quat upper_arm_from_forearm(const ArmAngles& a) {
  return rotation(a.elbow_flexion_rad, Vec3::UnitX()) * rotation(a.supination_rad, Vec3::UnitY());
}

ArmPose arm_pose(const ArmGeometry& g, const ArmAngles& a) {
  const Quat W_from_S = rotation(g.heading_rad, Vec3::UnitZ());
  const Quat S_from_U = S_from_upper_arm(a);
  const Quat U_from_F = upper_arm_from_forearm(a);
  const Quat W_from_U = (W_from_S * S_from_U).normalized();
  ArmPose pose;
  pose.W_from_F = (W_from_U * U_from_F).normalized();
  pose.elbow_p_W_m = g.shoulder_p_W_m + W_from_U * Vec3(0.0, g.upper_arm_m, 0.0);
  pose.strap_p_W_m = pose.elbow_p_W_m + pose.W_from_F * Vec3(0.0, g.strap_to_elbow_m, 0.0);
  pose.imu_p_W_m = pose.strap_p_W_m + pose.W_from_F * Vec3(g.strap_radius_m, 0.0, 0.0);
  pose.W_from_A = (pose.W_from_F * g.F_from_A).normalized();
  return pose;
}

SensorTrajectory imu_trajectory(const ArmGeometry& geometry, const ScriptedMotion& motion, double dt_s) {
  require_positive(dt_s, "dt_s");
  require_positive(motion.duration_s, "motion.duration_s");
  if (!motion.angles) throw_invalid("motion.angles", "no angle function");
  if (!geometry.shoulder_p_W_m.allFinite()) throw_invalid("geometry.shoulder_p_W_m", "must be finite");
  require_finite(geometry.heading_rad, "geometry.heading_rad");
  require_positive(geometry.upper_arm_m, "geometry.upper_arm_m");
  require_non_negative(geometry.strap_to_elbow_m, "geometry.strap_to_elbow_m");
  require_non_negative(geometry.strap_radius_m, "geometry.strap_radius_m");
  if (!geometry.F_from_A.coeffs().allFinite() || std::abs(geometry.F_from_A.norm() - 1.0) > 1e-6) {
    throw_invalid("geometry.F_from_A", "must be a unit quaternion");
  }
  const double steps = motion.duration_s / dt_s;
  if (steps > 1e8) throw Error(ErrorCode::kResourceExhausted, "dt_s", "more than 1e8 poses");

  SensorTrajectory out;
  out.dt_s = dt_s;
  out.t0_s = -2.0 * dt_s;
  const auto n = static_cast<std::size_t>(std::ceil(steps - 1e-9)) + 5;
  out.p_W_m.reserve(n);
  out.W_from_A.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = std::clamp(out.t0_s + static_cast<double>(k) * dt_s, 0.0, motion.duration_s);
    const ArmPose pose = arm_pose(geometry, motion.angles(t));
    out.p_W_m.push_back(pose.imu_p_W_m);
    out.W_from_A.push_back(pose.W_from_A);
  }
  return out;
}

ScriptedMotion forearm_rolling(const ForearmRollingOptions& o) {
  require_finite(o.amplitude_rad, "amplitude_rad");
  require_positive(o.period_s, "period_s");
  check_repetitions(o.repetitions);
  require_non_negative(o.hold_s, "hold_s");
  require_finite(o.elbow_flexion_rad, "elbow_flexion_rad");
  ScriptedMotion m;
  const double cycles = o.repetitions;
  m.duration_s = 2.0 * o.hold_s + cycles * o.period_s;
  m.angles = [o, cycles](double t) {
    ArmAngles a;
    a.elbow_flexion_rad = o.elbow_flexion_rad;
    const double u = std::clamp((t - o.hold_s) / o.period_s, 0.0, cycles);
    // Fade in over the first half cycle and out over the last (never more than half the motion).
    const double fade = std::min(0.5, cycles / 2.0);
    const double envelope = smootherstep(std::min(u, cycles - u) / fade);
    a.supination_rad = o.amplitude_rad * envelope * std::sin(2.0 * pi * u);
    return a;
  };
  return m;
}

ScriptedMotion arm_raising(const ArmRaisingOptions& o) {
  require_finite(o.peak_rad, "peak_rad");
  require_positive(o.raise_s, "raise_s");
  require_positive(o.lower_s, "lower_s");
  require_non_negative(o.pause_top_s, "pause_top_s");
  require_non_negative(o.pause_bottom_s, "pause_bottom_s");
  check_repetitions(o.repetitions);
  require_non_negative(o.hold_s, "hold_s");
  ScriptedMotion m;
  const double cycle = o.raise_s + o.pause_top_s + o.lower_s + o.pause_bottom_s;
  // The last repetition ends after lowering; hold_s follows.
  m.duration_s = 2.0 * o.hold_s + o.repetitions * cycle - o.pause_bottom_s;
  m.angles = [o, cycle](double t) {
    const double moving = std::max(0.0, t - o.hold_s);
    const double rep = std::min(std::floor(moving / cycle), static_cast<double>(o.repetitions - 1));
    const double s = moving - rep * cycle;  // time within this repetition
    double elevation = 0.0;
    if (s < o.raise_s) {
      elevation = smootherstep(s / o.raise_s);
    } else if (s < o.raise_s + o.pause_top_s) {
      elevation = 1.0;
    } else {
      elevation = 1.0 - smootherstep((s - o.raise_s - o.pause_top_s) / o.lower_s);
    }
    ArmAngles a;
    if (o.plane == ArmRaisingOptions::Plane::kFrontal) {
      a.shoulder_abduction_rad = o.peak_rad * elevation;
    } else {
      a.shoulder_flexion_rad = o.peak_rad * elevation;
    }
    return a;
  };
  return m;
}

ArmAngles calibration_pose_angles() {
  ArmAngles a;
  a.shoulder_abduction_rad = pi / 2;
  a.humeral_rotation_rad = pi / 2;
  a.elbow_flexion_rad = pi / 2;
  return a;
}

ScriptedMotion calibration_hold(const CalibrationHoldOptions& o) {
  require_positive(o.duration_s, "duration_s");
  require_non_negative(o.sway_rad, "sway_rad");
  require_positive(o.sway_hz, "sway_hz");
  ScriptedMotion m;
  m.duration_s = o.duration_s;
  m.angles = [o](double t) {
    ArmAngles a = calibration_pose_angles();
    // Sway faded in and out so that the hold starts and ends at rest; incommensurate phases
    // per joint so that the joints do not move in lockstep.
    const double fade = smootherstep(std::min(t, o.duration_s - t) / std::min(1.0, o.duration_s / 2));
    const double w = 2.0 * pi * o.sway_hz;
    a.shoulder_abduction_rad += o.sway_rad * fade * std::sin(w * t);
    a.shoulder_flexion_rad += o.sway_rad * fade * std::sin(1.37 * w * t + 0.5);
    a.humeral_rotation_rad += o.sway_rad * fade * std::sin(0.81 * w * t + 1.1);
    a.elbow_flexion_rad += o.sway_rad * fade * std::sin(1.19 * w * t + 2.0);
    a.supination_rad += o.sway_rad * fade * std::sin(0.67 * w * t + 0.3);
    return a;
  };
  return m;
}

}  // namespace posefuse::sim
