#include "sim/bvh_sensor.hpp"

#include <algorithm>
#include <cmath>

#include "common/error.hpp"
#include "sim/option_checks.hpp"
#include "sim/uniform_cubic_spline.hpp"

namespace posefuse::sim {

SensorTrajectory bvh_sensor_trajectory(const BvhClip& clip, const BvhSensorMount& mount, double metres_per_unit,
                                       double smoothing_s, double dt_s) {
  require_positive(dt_s, "dt_s");
  require_non_negative(smoothing_s, "smoothing_s");
  require_positive(clip.frame_time_s, "clip.frame_time_s");
  const int joint = clip.skeleton.find(mount.joint);
  if (joint < 0) throw_invalid("mount.joint", "no joint named '" + mount.joint + "' in the clip");
  if (clip.frame_count() < 2) throw_invalid("clip.frames", "needs at least 2 frames");
  if (!mount.offset_joint_m.allFinite()) throw_invalid("mount.offset_joint_m", "must be finite");
  if (!mount.joint_from_A.coeffs().allFinite() || std::abs(mount.joint_from_A.norm() - 1.0) > 1e-6) {
    throw_invalid("mount.joint_from_A", "must be a unit quaternion");
  }
  const double steps = clip.duration_s() / dt_s;
  if (steps > 1e8) throw Error(ErrorCode::kResourceExhausted, "dt_s", "more than 1e8 poses");

  const auto j = static_cast<std::size_t>(joint);
  std::vector<Eigen::VectorXd> frames;
  frames.reserve(clip.frames.size());
  Quat previous = Quat::Identity();
  for (std::size_t f = 0; f < clip.frames.size(); ++f) {
    const BvhWorldPose pose = forward_kinematics(clip.skeleton, clip.frames[f], metres_per_unit);
    Quat q = (pose.W_from_joint[j] * mount.joint_from_A).normalized();
    if (f > 0) q = geometry::same_hemisphere(q, previous);
    previous = q;
    const Vec3 p = pose.p_W_m[j] + pose.W_from_joint[j] * mount.offset_joint_m;
    Eigen::VectorXd v(7);
    v << p, q.w(), q.x(), q.y(), q.z();
    frames.push_back(v);
  }
  const UniformCubicSpline spline(0.0, clip.frame_time_s, gaussian_smooth(frames, smoothing_s / clip.frame_time_s));

  SensorTrajectory out;
  out.t0_s = 0.0;
  out.dt_s = dt_s;
  const auto n = static_cast<std::size_t>(std::floor(steps + 1e-9)) + 1;
  out.p_W_m.reserve(n);
  out.W_from_A.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::VectorXd v = spline.at(static_cast<double>(k) * dt_s);
    out.p_W_m.push_back(v.head<3>());
    out.W_from_A.push_back(Quat(v[3], v[4], v[5], v[6]).normalized());
  }
  return out;
}

}  // namespace posefuse::sim
