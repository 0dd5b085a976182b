#pragma once
// The residual blocks of paper 2's energy (II-D, II-E; eq. 13-14): each term of eq. 4 written as
// a small residual vector r with E_term = |r|^2, and its analytic Jacobian with respect to the
// pose theta (dense rows over the layout's N DOF) and, for the data term, to the sample's
// correspondence (u, v). The weights lambda / normalisations 1/N of eq. 5-12 are folded into
// each block's `weight` as square roots, so the total energy is the plain sum of squares.
//
// Blocks are value types with no state beyond their constants; the fitter decides which
// points enter which block and takes their D_2D / D_3D targets at the pose it evaluates.
#include <Eigen/Core>

#include "body/body_evaluator.hpp"
#include "body/surface.hpp"
#include "body/surface_pose_jacobians.hpp"
#include "raycast/depth_camera.hpp"

namespace posefuse::fit {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using PoseRows3 = Eigen::Matrix<double, 3, Eigen::Dynamic>;

// Data term, eq. 5, one sample: r = [position_weight (S_p(nu) - p); normal_weight (S_n(nu) - n)]
// with position_weight = 1 / (sigma_p sqrt(N_s)) and normal_weight = 1 / (sigma_n sqrt(N_s)).
struct DataResidual {
  Eigen::Vector3d point_K = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal_K = Eigen::Vector3d::UnitZ();
  double position_weight = 1, normal_weight = 1;

  Vector6d residual(const body::BodySurface& surface, const body::SurfacePoint& nu) const;
  // r (6), d r / d theta (6 x N, overwritten) and d r / d (u, v) (6 x 2). `eval` produced the
  // vertices of `surface` with pose derivatives.
  void evaluate(const body::BodySurface& surface, const body::BodyEvaluator& eval, const body::SurfacePoint& nu,
                Eigen::Ref<Vector6d> r, Eigen::Ref<Eigen::MatrixXd> d_r_d_theta,
                Eigen::Ref<Eigen::Matrix<double, 6, 2>> d_r_d_uv) const;
  // The same, with the pose Jacobians from `jacobians` (shared per-vertex work; the fitter's path)
  // and packed: d_r_d_theta is 6 x m, column c the derivative by DOF
  // jacobians.face_columns(nu.face)[c] (m that list's size; all other DOFs give zero).
  void evaluate_packed(const body::BodySurface& surface, const body::BodyEvaluator& eval,
                       body::SurfacePoseJacobians& jacobians, const body::SurfacePoint& nu, Eigen::Ref<Vector6d> r,
                       Eigen::Ref<Eigen::MatrixXd> d_r_d_theta, Eigen::Ref<Eigen::Matrix<double, 6, 2>> d_r_d_uv) const;
  // d r / d beta (6 x B, overwritten); `eval` produced the vertices of `surface` with
  // Derivatives::kPoseAndShape (paper 2, III-B).
  void evaluate_shape(const body::BodySurface& surface, const body::BodyEvaluator& eval, const body::SurfacePoint& nu,
                      Eigen::Ref<Eigen::MatrixXd> d_r_d_beta) const;

 private:
  // r, the weights applied to the unweighted S_p / S_n rows of d_r_d_theta, and d r / d (u, v).
  void finish(const body::BodySurface& surface, const body::SurfacePoint& nu, Eigen::Ref<Vector6d> r,
              Eigen::Ref<Eigen::MatrixXd> d_r_d_theta, Eigen::Ref<Eigen::Matrix<double, 6, 2>> d_r_d_uv) const;
};

// bg (eq. 6) and bgJoint (eq. 7), one point x(theta): r = weight |Pi(x) - q|, where q is the
// silhouette target of Pi(x) (D_2D, the fitter's silhouette_target; the term is zero for points
// that project inside the silhouette, and the fitter does not create blocks for those).
// weight = sqrt(lambda / H) or sqrt(lambda / |J_bg|).
//
// Two linearisations of the same energy. evaluate: the distance, one residual. The closest
// silhouette pixel q slides along the silhouette's edge as x moves, so the energy changes only
// with the distance, and its derivative is u^T dPi/dtheta with u the unit offset
// (Pi(x) - q) / |Pi(x) - q|. evaluate_offset: the offset with q held (paper 2, two residuals),
// which credits a step along the edge with a decrease the energy does not have, the slow
// convergence of point-to-point ICP. The fitter uses the offsets unless
// FitOptions::linearise_distances (pose fit only).
struct SilhouetteResidual {
  Eigen::Vector2d target_pixel = Eigen::Vector2d::Zero();
  double weight = 1;

  // weight (Pi(x) - q) and r = its norm. Require x.z() > 0.
  Eigen::Vector2d offset(const raycast::DepthIntrinsics& intrinsics, const Eigen::Vector3d& x_K) const;
  double residual(const raycast::DepthIntrinsics& intrinsics, const Eigen::Vector3d& x_K) const {
    return offset(intrinsics, x_K).norm();
  }
  // d_x_d_theta: 3 x N Jacobian of the point; writes r and d r / d theta (1 x N; zero where Pi(x)
  // is q itself).
  void evaluate(const raycast::DepthIntrinsics& intrinsics, const Eigen::Vector3d& x_K,
                const Eigen::Ref<const PoseRows3>& d_x_d_theta, double& r,
                Eigen::Ref<Eigen::MatrixXd> d_r_d_theta) const;
  // The offset and its Jacobian, q held (2 x N).
  void evaluate_offset(const raycast::DepthIntrinsics& intrinsics, const Eigen::Vector3d& x_K,
                       const Eigen::Ref<const PoseRows3>& d_x_d_theta, Eigen::Ref<Eigen::Vector2d> r,
                       Eigen::Ref<Eigen::MatrixXd> d_r_d_theta) const;
};

// float (eq. 12), one point: r = weight |x - D_3D(x)| with D_3D(x) the closest point behind the
// observed surface (BehindSurfaceMap); weight = sqrt(lambda_float / Q). Linearised as
// SilhouetteResidual: the distance (evaluate) or the offset with the target held (evaluate_offset).
struct BehindResidual {
  Eigen::Vector3d target_K = Eigen::Vector3d::Zero();
  double weight = 1;

  Eigen::Vector3d offset(const Eigen::Vector3d& x_K) const { return weight * (x_K - target_K); }
  double residual(const Eigen::Vector3d& x_K) const { return offset(x_K).norm(); }
  // r and d r / d theta (1 x N; zero where x is its target).
  void evaluate(const Eigen::Vector3d& x_K, const Eigen::Ref<const PoseRows3>& d_x_d_theta, double& r,
                Eigen::Ref<Eigen::MatrixXd> d_r_d_theta) const;
  // The offset and its Jacobian, target held (3 x N).
  void evaluate_offset(const Eigen::Vector3d& x_K, const Eigen::Ref<const PoseRows3>& d_x_d_theta,
                       Eigen::Ref<Eigen::Vector3d> r, Eigen::Ref<Eigen::MatrixXd> d_r_d_theta) const;
};

// limit (eq. 8): one residual per limited DOF d (the N_theta - 6 non-global ones),
// r_d = weight (max(0, min_d - theta_d) + max(0, theta_d - max_d)), weight = sqrt(lambda / (N - 6)).
// theta_d is the joint angle psi_d because each DOF adds theta_d * axis to its joint's rotation
// vector (body/pose_parameters.hpp).
struct LimitResidual {
  double weight = 1;

  // Number of residuals: the layout's limited DOFs.
  static int size(const body::PoseLayout& layout);
  // r (size) and d r / d theta (size x N, overwritten).
  void evaluate(const body::PoseLayout& layout, const Eigen::Ref<const Eigen::VectorXd>& theta,
                Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> d_r_d_theta) const;
  double energy(const body::PoseLayout& layout, const Eigen::Ref<const Eigen::VectorXd>& theta) const;
};

// Bound on the free shape parameters while shape and pose are fitted together (III-B; ours: the
// paper fits beta without a stated bound). The same soft form as eq. 8, one residual per free beta:
// r_b = weight (max(0, -bound - beta_b) + max(0, beta_b - bound)), bound = the range the rough
// shape keeps (RoughShapeOptions::max_abs_beta), weight = sqrt(lambda_limit / B_free). Beyond
// about 3 the template's shape directions leave the range of human bodies.
struct ShapeBoundResidual {
  double bound = 3.0;
  double weight = 1;

  // r (free.size()) and d r / d beta_free (free.size() x free.size(), overwritten).
  void evaluate(const Eigen::Ref<const Eigen::VectorXd>& beta_free, Eigen::Ref<Eigen::VectorXd> r,
                Eigen::Ref<Eigen::MatrixXd> d_r_d_beta_free) const;
  double energy(const Eigen::Ref<const Eigen::VectorXd>& beta_free) const;
};

// imu (eq. 9-11), one forearm: r = weight (Pi(J_wrist - J_elbow) - e), e the forearm direction
// from the wrist IMU in K (unit); weight = sqrt(lambda_imu).
struct ForearmDirectionResidual {
  int elbow = body::kLeftElbow, wrist = body::kLeftWrist;
  Eigen::Vector3d expected_K = Eigen::Vector3d::UnitX();
  double weight = 1;

  Eigen::Vector3d residual(const Eigen::Matrix3Xd& joints_K) const;
  // joint_jacobian: BodyEvaluator::joint_pose_jacobian() (72 x N).
  void evaluate(const Eigen::Matrix3Xd& joints_K, const Eigen::MatrixXd& joint_jacobian, Eigen::Ref<Eigen::Vector3d> r,
                Eigen::Ref<Eigen::MatrixXd> d_r_d_theta) const;
};

}  // namespace posefuse::fit
