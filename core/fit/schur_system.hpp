#pragma once
// The LM normal equations of paper 2, eq. 16, over the pose theta (N DOF) and the n
// correspondences (u_i, v_i) together, solved by eliminating the correspondences.
//
// Each correspondence enters only its own 6 data residuals (eq. 5), so J^T J has the arrow
// structure [[H, E_1 .. E_n], [E_i^T, C_i]] with 2 x 2 blocks C_i. The Schur complement
//   (H + D - sum_i E_i C_i'^-1 E_i^T) dtheta = -g + sum_i E_i C_i'^-1 g_i,
//   du_i = -C_i'^-1 (g_i + E_i^T dtheta),        C_i' = C_i + gamma diag(C_i)
// costs O(n N^2) instead of O((N + 2n)^3); the reduced N x N system is solved by dense LDLT.
// Damping (ours, Marquardt): gamma * diag(J^T J), each diagonal entry clamped below by
// min_diagonal so that a DOF no residual sees still gets a finite, tiny step.
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <span>
#include <vector>

namespace posefuse::fit {

using UvJacobian = Eigen::Matrix<double, 6, 2>;

class SchurSystem {
 public:
  static constexpr double kMinDiagonal = 1e-6;
  static constexpr int kMaxPose = 96;  // largest pose dimension (full body: 48)

  // Starts new normal equations for N pose DOF and n correspondences.
  void reset(int num_pose, int num_blocks);
  // The 6 data residuals r of correspondence i: their pose Jacobian A (6 x N, mostly zero
  // columns: only the DOFs that move the face's vertices) and their (u, v) Jacobian B. Only the
  // non-zero columns of A enter J^T J, which is why the blocks are added one by one.
  void add_block(int i, const Eigen::Ref<const Eigen::MatrixXd>& A, const UvJacobian& B,
                 const Eigen::Ref<const Eigen::Matrix<double, 6, 1>>& r);
  // The same with A given by its columns `columns` only (ascending DOF indices, all others zero):
  // packed is 6 x columns.size(), column c holding A's column columns[c]. Same result as the dense
  // form, without its scan for zero columns.
  void add_block(int i, std::span<const int> columns, const Eigen::Ref<const Eigen::MatrixXd>& packed,
                 const UvJacobian& B, const Eigen::Ref<const Eigen::Matrix<double, 6, 1>>& r);
  // Residual rows that depend on the pose only: J (k x N) and r (k).
  void add_pose_rows(const Eigen::Ref<const Eigen::MatrixXd>& J, const Eigen::Ref<const Eigen::VectorXd>& r);

  // Shorthand: reset, then rows 6i .. 6i + 5 of J_pose as block i (i < num_blocks) with J_uv[i],
  // the remaining rows as pose rows.
  void linearise(const Eigen::Ref<const Eigen::MatrixXd>& J_pose, const Eigen::Ref<const Eigen::VectorXd>& r,
                 const std::vector<UvJacobian>& J_uv, int num_blocks);

  // Solves (J^T J + gamma diag(J^T J)) delta = -J^T r for delta = (d_pose, d_uv[0 .. n-1]).
  // The pose DOFs in `held` (ascending) keep d_pose = 0: the system is solved over the other
  // unknowns, as if the held DOFs' columns were not in J. Returns false when the reduced system is
  // not positive definite (the caller raises gamma).
  bool solve(double gamma, Eigen::VectorXd& d_pose, std::vector<Eigen::Vector2d>& d_uv, std::span<const int> held = {});
  // Decrease of the quadratic model |r + J delta|^2 for a step solve() returned with this gamma:
  // gamma delta^T D delta - g^T delta (for LM's gain ratio).
  double predicted_decrease(double gamma, const Eigen::VectorXd& d_pose,
                            const std::vector<Eigen::Vector2d>& d_uv) const;

 private:
  // diag(J_pose^T J_pose), entry d.
  double diagonal(int d) const { return hessian_(d, d) + data_diagonal_[d]; }

  int num_pose_ = 0, num_blocks_ = 0;
  // J_pose^T J_pose = hessian_ + sum_i A_i^T A_i: the pose rows' part (lower triangle filled);
  // the blocks' part is formed in solve() with their Schur terms, its diagonal kept here.
  Eigen::MatrixXd hessian_;
  Eigen::VectorXd data_diagonal_;
  Eigen::VectorXd gradient_;  // g = J_pose^T r
  // E_i = A_i^T B_i, stored packed: rows block_columns_[block_begin_[i] ..] of E_i, its two
  // columns apart (contiguous for the Schur products).
  std::vector<int> block_begin_, block_columns_;
  std::vector<double> block_jacobian_;  // A_i's column for each entry of block_columns_ (6 each)
  std::vector<double> coupling_u_, coupling_v_;
  std::vector<Eigen::Matrix2d> block_hessian_;   // C_i = B_i^T B_i
  std::vector<Eigen::Vector2d> block_gradient_;  // g_i = B_i^T r_i
  // Work space.
  Eigen::MatrixXd reduced_;
  Eigen::VectorXd rhs_;
  std::vector<Eigen::Matrix2d> damped_inverse_;
  std::vector<int> free_;  // the DOFs solve() does not hold
  Eigen::MatrixXd free_system_;
  Eigen::VectorXd free_rhs_, free_step_;
  Eigen::LDLT<Eigen::MatrixXd, Eigen::Lower> ldlt_;
};

}  // namespace posefuse::fit
