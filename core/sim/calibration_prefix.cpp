#include "sim/calibration_prefix.hpp"

#include <algorithm>

#include <Eigen/Geometry>

#include "common/error.hpp"
#include "geometry/quaternion.hpp"

namespace posefuse::sim {

namespace {

double smootherstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * x * (10.0 + x * (-15.0 + 6.0 * x));
}

// theta layout all_joints: translation, then one rotation vector per joint.
Eigen::VectorXd blend(const Eigen::VectorXd& a, const Eigen::VectorXd& b, double w) {
  Eigen::VectorXd out(a.size());
  out.head<3>() = (1.0 - w) * a.head<3>() + w * b.head<3>();
  for (Eigen::Index i = 3; i + 2 < a.size(); i += 3) {
    const geometry::Quat qa = geometry::quat_from_rotation_vector(a.segment<3>(i));
    const geometry::Quat qb = geometry::same_hemisphere(geometry::quat_from_rotation_vector(b.segment<3>(i)), qa);
    out.segment<3>(i) = geometry::rotation_vector_from_quat(qa.slerp(w, qb));
  }
  return out;
}

}  // namespace

double calibration_hold_end_s(const BodyMotion& motion) {
  for (const MotionPhase& phase : motion.phases) {
    if (phase.name == "calibration_hold") return phase.end_s;
  }
  throw_invalid("motion.phases", "has no calibration_hold");
}

BodyMotion with_calibration_prefix(const BodyMotion& calibration, const BodyMotion& clip, double blend_s) {
  const double hold_end = calibration_hold_end_s(calibration);
  const double clip0 = hold_end + blend_s;
  const Eigen::VectorXd held = calibration.poses(hold_end);
  BodyMotion out;
  out.duration_s = clip0 + clip.duration_s;
  out.warnings = calibration.warnings;
  out.warnings.insert(out.warnings.end(), clip.warnings.begin(), clip.warnings.end());
  const sim::PoseSequence calib = calibration.poses, moving = clip.poses;
  out.poses = [=](double t) -> Eigen::VectorXd {
    if (t <= hold_end) return calib(t);
    if (t >= clip0) return moving(t - clip0);
    return blend(held, moving(t - clip0), smootherstep((t - hold_end) / blend_s));
  };
  for (const MotionPhase& p : calibration.phases) {
    if (p.end_s <= hold_end) out.phases.push_back(p);
  }
  for (MotionPhase p : clip.phases) {
    p.begin_s += clip0;
    p.end_s += clip0;
    out.phases.push_back(p);
  }
  return out;
}

BodyMotion with_calibration_suffix(const BodyMotion& clip, const BodyMotion& calibration, double blend_s) {
  if (clip.duration_s < blend_s) {
    throw_invalid("motion.duration_s", "the clip (" + std::to_string(clip.duration_s) +
                                           " s) is shorter than the blend into the calibration pose (" +
                                           std::to_string(blend_s) + " s)");
  }
  const double calib0 = clip.duration_s;
  const double blend_begin = calib0 - blend_s;
  BodyMotion out;
  out.duration_s = calib0 + calibration.duration_s;
  out.warnings = clip.warnings;
  out.warnings.insert(out.warnings.end(), calibration.warnings.begin(), calibration.warnings.end());
  const sim::PoseSequence moving = clip.poses, calib = calibration.poses;
  out.poses = [=](double t) -> Eigen::VectorXd {
    if (t <= blend_begin) return moving(t);
    if (t >= calib0) return calib(t - calib0);
    return blend(moving(t), calib(t - calib0), smootherstep((t - blend_begin) / blend_s));
  };
  out.phases = clip.phases;
  for (MotionPhase p : calibration.phases) {
    p.begin_s += calib0;
    p.end_s += calib0;
    out.phases.push_back(p);
  }
  return out;
}

}  // namespace posefuse::sim
