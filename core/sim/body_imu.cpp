#include "sim/body_imu.hpp"

#include <cmath>

#include "common/error.hpp"
#include "sim/option_checks.hpp"

namespace posefuse::sim {
namespace {

constexpr int kMargin = 2;  // grid points beyond each end that the 5-point stencils need

std::size_t grid_size(double begin_s, double end_s, double dt_s) {
  const double steps = (end_s - begin_s) / dt_s;
  if (steps > 1e8) throw Error(ErrorCode::kResourceExhausted, "dt_s", "more than 1e8 poses");
  return static_cast<std::size_t>(std::ceil(steps - 1e-9)) + 1 + 2 * kMargin;
}

void check_unit(const Quat& q, const char* field) {
  if (!q.coeffs().allFinite() || std::abs(q.norm() - 1.0) > 1e-6) throw_invalid(field, "must be a unit quaternion");
}

}  // namespace

SensorTrajectory forearm_imu_trajectory(const BodyMotion& motion, const Eigen::Matrix3Xd& rest_joints,
                                        const ForearmStrap& strap, const Quat& W_from_R, double dt_s) {
  require_positive(dt_s, "dt_s");
  require_positive(motion.duration_s, "motion.duration_s");
  if (!motion.poses) throw_invalid("motion.poses", "is empty");
  validate(strap);
  check_unit(W_from_R, "W_from_R");
  const Quat rest_R_from_F = forearm_rest_R_from_F(rest_joints, strap.side);
  const body::PoseLayout layout = body::PoseLayout::all_joints();

  SensorTrajectory out;
  out.dt_s = dt_s;
  out.t0_s = -kMargin * dt_s;
  const std::size_t n = grid_size(0.0, motion.duration_s, dt_s);
  out.p_W_m.reserve(n);
  out.W_from_A.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = out.t0_s + static_cast<double>(k) * dt_s;
    const Eigen::VectorXd theta = motion.poses(t);
    if (theta.size() != layout.size() || !theta.allFinite()) {
      throw_invalid("motion.poses", "gave a theta of size " + std::to_string(theta.size()) + " (all_joints has " +
                                        std::to_string(layout.size()) +
                                        ") or non-finite values at t = " + std::to_string(t) + " s");
    }
    const ForearmPose pose = forearm_pose(pose_skeleton(rest_joints, layout, theta), rest_R_from_F, strap);
    out.p_W_m.push_back(W_from_R * pose.imu_R_m);
    out.W_from_A.push_back((W_from_R * pose.R_from_A).normalized());
  }
  return out;
}

SensorTrajectory base_imu_trajectory(const Eigen::Isometry3d& K_from_R, const Quat& W_from_R, const BaseImuMount& mount,
                                     double t_begin_s, double t_end_s, double dt_s) {
  require_positive(dt_s, "dt_s");
  require_interval(t_begin_s, t_end_s, "t_end_s");
  if (!K_from_R.matrix().allFinite()) throw_invalid("K_from_R", "is not finite");
  check_unit(W_from_R, "W_from_R");
  check_unit(mount.K_from_B, "mount.K_from_B");
  if (!mount.p_K_m.allFinite()) throw_invalid("mount.p_K_m", "is not finite");
  const Eigen::Isometry3d R_from_K = K_from_R.inverse();
  const Quat W_from_B = (W_from_R * Quat(R_from_K.linear()) * mount.K_from_B).normalized();
  const Vec3 p_W = W_from_R * (R_from_K * mount.p_K_m);
  SensorTrajectory out;
  out.dt_s = dt_s;
  out.t0_s = t_begin_s - kMargin * dt_s;
  const std::size_t n = std::max<std::size_t>(grid_size(t_begin_s, t_end_s, dt_s), 2 * kMargin + 2);
  out.p_W_m.assign(n, p_W);
  out.W_from_A.assign(n, W_from_B);
  return out;
}

}  // namespace posefuse::sim
