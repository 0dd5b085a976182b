#include "fit/residual_blocks.hpp"

#include <algorithm>
#include <cmath>

#include "fit/camera_projection.hpp"

namespace posefuse::fit {

Vector6d DataResidual::residual(const body::BodySurface& surface, const body::SurfacePoint& nu) const {
  Vector6d r;
  r.head<3>() = position_weight * (surface.position(nu) - point_K);
  r.tail<3>() = normal_weight * (surface.normal(nu) - normal_K);
  return r;
}

void DataResidual::evaluate(const body::BodySurface& surface, const body::BodyEvaluator& eval,
                            const body::SurfacePoint& nu, Eigen::Ref<Vector6d> r,
                            Eigen::Ref<Eigen::MatrixXd> d_r_d_theta,
                            Eigen::Ref<Eigen::Matrix<double, 6, 2>> d_r_d_uv) const {
  d_r_d_theta.setZero();
  surface.position_pose_jacobian(nu, eval, d_r_d_theta.topRows<3>());
  surface.normal_pose_jacobian(nu, eval, d_r_d_theta.bottomRows<3>());
  finish(surface, nu, r, d_r_d_theta, d_r_d_uv);
}

void DataResidual::evaluate_packed(const body::BodySurface& surface, const body::BodyEvaluator& eval,
                                   body::SurfacePoseJacobians& jacobians, const body::SurfacePoint& nu,
                                   Eigen::Ref<Vector6d> r, Eigen::Ref<Eigen::MatrixXd> d_r_d_theta,
                                   Eigen::Ref<Eigen::Matrix<double, 6, 2>> d_r_d_uv) const {
  jacobians.evaluate_packed(surface, eval, nu, d_r_d_theta.topRows<3>(), d_r_d_theta.bottomRows<3>());
  finish(surface, nu, r, d_r_d_theta, d_r_d_uv);
}

void DataResidual::finish(const body::BodySurface& surface, const body::SurfacePoint& nu, Eigen::Ref<Vector6d> r,
                          Eigen::Ref<Eigen::MatrixXd> d_r_d_theta,
                          Eigen::Ref<Eigen::Matrix<double, 6, 2>> d_r_d_uv) const {
  r = residual(surface, nu);
  d_r_d_theta.topRows<3>() *= position_weight;
  d_r_d_theta.bottomRows<3>() *= normal_weight;
  d_r_d_uv.topRows<3>() = position_weight * surface.position_uv_jacobian(nu);
  d_r_d_uv.bottomRows<3>() = normal_weight * surface.normal_uv_jacobian(nu);
}

void DataResidual::evaluate_shape(const body::BodySurface& surface, const body::BodyEvaluator& eval,
                                  const body::SurfacePoint& nu, Eigen::Ref<Eigen::MatrixXd> d_r_d_beta) const {
  d_r_d_beta.setZero();
  surface.position_shape_jacobian(nu, eval, d_r_d_beta.topRows<3>());
  surface.normal_shape_jacobian(nu, eval, d_r_d_beta.bottomRows<3>());
  d_r_d_beta.topRows<3>() *= position_weight;
  d_r_d_beta.bottomRows<3>() *= normal_weight;
}

namespace {

// r = weight |offset| and its 1 x N Jacobian weight u^T d_offset, u = offset / |offset|; a zero
// offset has no direction, and its row is zero.
template <int Dim>
void distance_residual(const Eigen::Matrix<double, Dim, 1>& offset,
                       const Eigen::Ref<const Eigen::Matrix<double, Dim, Eigen::Dynamic>>& d_offset, double weight,
                       double& r, Eigen::Ref<Eigen::MatrixXd> d_r_d_theta) {
  const double distance = offset.norm();
  r = weight * distance;
  if (distance > 0) d_r_d_theta.noalias() = ((weight / distance) * offset.transpose()) * d_offset;
  else d_r_d_theta.setZero();
}

}  // namespace

Eigen::Vector2d SilhouetteResidual::offset(const raycast::DepthIntrinsics& intrinsics,
                                           const Eigen::Vector3d& x_K) const {
  return weight * (project_with_jacobian(intrinsics, x_K).pixel - target_pixel);
}

void SilhouetteResidual::evaluate(const raycast::DepthIntrinsics& intrinsics, const Eigen::Vector3d& x_K,
                                  const Eigen::Ref<const PoseRows3>& d_x_d_theta, double& r,
                                  Eigen::Ref<Eigen::MatrixXd> d_r_d_theta) const {
  const Projection p = project_with_jacobian(intrinsics, x_K);
  const Eigen::Matrix<double, 2, Eigen::Dynamic> d_pixel = p.d_pixel_d_point * d_x_d_theta;
  distance_residual<2>(p.pixel - target_pixel, d_pixel, weight, r, d_r_d_theta);
}

void SilhouetteResidual::evaluate_offset(const raycast::DepthIntrinsics& intrinsics, const Eigen::Vector3d& x_K,
                                         const Eigen::Ref<const PoseRows3>& d_x_d_theta, Eigen::Ref<Eigen::Vector2d> r,
                                         Eigen::Ref<Eigen::MatrixXd> d_r_d_theta) const {
  const Projection p = project_with_jacobian(intrinsics, x_K);
  r = weight * (p.pixel - target_pixel);
  d_r_d_theta.noalias() = (weight * p.d_pixel_d_point) * d_x_d_theta;
}

void BehindResidual::evaluate(const Eigen::Vector3d& x_K, const Eigen::Ref<const PoseRows3>& d_x_d_theta, double& r,
                              Eigen::Ref<Eigen::MatrixXd> d_r_d_theta) const {
  distance_residual<3>(x_K - target_K, d_x_d_theta, weight, r, d_r_d_theta);
}

void BehindResidual::evaluate_offset(const Eigen::Vector3d& x_K, const Eigen::Ref<const PoseRows3>& d_x_d_theta,
                                     Eigen::Ref<Eigen::Vector3d> r, Eigen::Ref<Eigen::MatrixXd> d_r_d_theta) const {
  r = offset(x_K);
  d_r_d_theta = weight * d_x_d_theta;
}

int LimitResidual::size(const body::PoseLayout& layout) {
  return static_cast<int>(
      std::count_if(layout.dofs().begin(), layout.dofs().end(), [](const body::Dof& d) { return d.limited; }));
}

void LimitResidual::evaluate(const body::PoseLayout& layout, const Eigen::Ref<const Eigen::VectorXd>& theta,
                             Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> d_r_d_theta) const {
  d_r_d_theta.setZero();
  int row = 0;
  for (int d = 0; d < layout.size(); ++d) {
    const body::Dof& dof = layout.dof(d);
    if (!dof.limited) continue;
    // Below the range the residual grows as theta falls (slope -1), above it as theta rises.
    if (theta[d] < dof.min_rad) {
      r[row] = weight * (dof.min_rad - theta[d]);
      d_r_d_theta(row, d) = -weight;
    } else if (theta[d] > dof.max_rad) {
      r[row] = weight * (theta[d] - dof.max_rad);
      d_r_d_theta(row, d) = weight;
    } else {
      r[row] = 0;
    }
    ++row;
  }
}

double LimitResidual::energy(const body::PoseLayout& layout, const Eigen::Ref<const Eigen::VectorXd>& theta) const {
  double sum = 0;
  for (int d = 0; d < layout.size(); ++d) {
    const body::Dof& dof = layout.dof(d);
    if (!dof.limited) continue;
    const double excess = std::max(0.0, dof.min_rad - theta[d]) + std::max(0.0, theta[d] - dof.max_rad);
    sum += excess * excess;
  }
  return weight * weight * sum;
}

void ShapeBoundResidual::evaluate(const Eigen::Ref<const Eigen::VectorXd>& beta_free, Eigen::Ref<Eigen::VectorXd> r,
                                  Eigen::Ref<Eigen::MatrixXd> d_r_d_beta_free) const {
  d_r_d_beta_free.setZero();
  for (Eigen::Index b = 0; b < beta_free.size(); ++b) {
    if (beta_free[b] < -bound) {
      r[b] = weight * (-bound - beta_free[b]);
      d_r_d_beta_free(b, b) = -weight;
    } else if (beta_free[b] > bound) {
      r[b] = weight * (beta_free[b] - bound);
      d_r_d_beta_free(b, b) = weight;
    } else {
      r[b] = 0;
    }
  }
}

double ShapeBoundResidual::energy(const Eigen::Ref<const Eigen::VectorXd>& beta_free) const {
  double sum = 0;
  for (Eigen::Index b = 0; b < beta_free.size(); ++b) {
    const double excess = std::max(0.0, std::abs(beta_free[b]) - bound);
    sum += excess * excess;
  }
  return weight * weight * sum;
}

Eigen::Vector3d ForearmDirectionResidual::residual(const Eigen::Matrix3Xd& joints_K) const {
  return weight * ((joints_K.col(wrist) - joints_K.col(elbow)).normalized() - expected_K);
}

void ForearmDirectionResidual::evaluate(const Eigen::Matrix3Xd& joints_K, const Eigen::MatrixXd& joint_jacobian,
                                        Eigen::Ref<Eigen::Vector3d> r, Eigen::Ref<Eigen::MatrixXd> d_r_d_theta) const {
  const Eigen::Vector3d forearm = joints_K.col(wrist) - joints_K.col(elbow);
  const double length = forearm.norm();
  const Eigen::Vector3d direction = forearm / length;
  r = weight * (direction - expected_K);
  // d Pi(a) = (I - Pi(a) Pi(a)^T) / |a| da (eq. 10-11).
  const Eigen::Matrix3d d_direction =
      (weight / length) * (Eigen::Matrix3d::Identity() - direction * direction.transpose());
  d_r_d_theta.noalias() =
      d_direction * (joint_jacobian.middleRows<3>(3 * wrist) - joint_jacobian.middleRows<3>(3 * elbow));
}

}  // namespace posefuse::fit
