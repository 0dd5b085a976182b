#include "fit/schur_system.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>

#include "common/error.hpp"

namespace posefuse::fit {

void SchurSystem::reset(int num_pose, int num_blocks) {
  if (num_pose <= 0 || num_pose > kMaxPose || num_blocks < 0)
    throw Error(ErrorCode::kInternal, "schur_system", "pose or block count out of range");
  num_pose_ = num_pose;
  num_blocks_ = num_blocks;
  hessian_.setZero(num_pose_, num_pose_);
  gradient_.setZero(num_pose_);
  block_begin_.assign(static_cast<size_t>(num_blocks) + 1, 0);
  block_columns_.clear();
  block_coupling_.clear();
  block_hessian_.resize(num_blocks);
  block_gradient_.resize(num_blocks);
}

void SchurSystem::add_block(int i, const Eigen::Ref<const Eigen::MatrixXd>& A, const UvJacobian& B,
                            const Eigen::Ref<const Eigen::Matrix<double, 6, 1>>& r) {
  if (i < 0 || i >= num_blocks_ || A.rows() != 6 || A.cols() != num_pose_ ||
      block_begin_[i] != static_cast<int>(block_columns_.size()))
    throw Error(ErrorCode::kInternal, "schur_system", "blocks out of order or Jacobian of the wrong size");
  // Gather the non-zero columns; fixed-capacity matrices keep this free of allocation.
  std::array<int, kMaxPose> columns;
  int m = 0;
  for (int c = 0; c < num_pose_; ++c)
    if (!A.col(c).isZero(0.0)) columns[m++] = c;
  Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, kMaxPose> packed(6, m);
  for (int k = 0; k < m; ++k) packed.col(k) = A.col(columns[k]);
  for (int a = 0; a < m; ++a) {
    const int row = columns[a];
    gradient_[row] += packed.col(a).dot(r);
    block_columns_.push_back(row);
    block_coupling_.emplace_back(B.transpose() * packed.col(a));
    for (int b = 0; b <= a; ++b) hessian_(row, columns[b]) += packed.col(a).dot(packed.col(b));  // lower triangle
  }
  block_begin_[i + 1] = static_cast<int>(block_columns_.size());
  block_hessian_[i].noalias() = B.transpose() * B;
  block_gradient_[i].noalias() = B.transpose() * r;
}

void SchurSystem::add_pose_rows(const Eigen::Ref<const Eigen::MatrixXd>& J, const Eigen::Ref<const Eigen::VectorXd>& r) {
  if (J.cols() != num_pose_ || J.rows() != r.size())
    throw Error(ErrorCode::kInternal, "schur_system", "pose rows of the wrong size");
  if (J.rows() == 0) return;
  hessian_.selfadjointView<Eigen::Lower>().rankUpdate(J.transpose());
  gradient_.noalias() += J.transpose() * r;
}

void SchurSystem::linearise(const Eigen::Ref<const Eigen::MatrixXd>& J_pose, const Eigen::Ref<const Eigen::VectorXd>& r,
                            const std::vector<UvJacobian>& J_uv, int num_blocks) {
  if (J_pose.rows() != r.size() || J_pose.rows() < 6 * num_blocks || static_cast<int>(J_uv.size()) < num_blocks)
    throw Error(ErrorCode::kInternal, "schur_system", "inconsistent residual and Jacobian sizes");
  reset(static_cast<int>(J_pose.cols()), num_blocks);
  for (int i = 0; i < num_blocks; ++i) add_block(i, J_pose.middleRows(6 * i, 6), J_uv[i], r.segment<6>(6 * i));
  const Eigen::Index rest = J_pose.rows() - 6 * num_blocks;
  add_pose_rows(J_pose.bottomRows(rest), r.tail(rest));
}

bool SchurSystem::solve(double gamma, Eigen::VectorXd& d_pose, std::vector<Eigen::Vector2d>& d_uv) {
  reduced_ = hessian_;
  for (int d = 0; d < num_pose_; ++d) reduced_(d, d) += gamma * std::max(hessian_(d, d), kMinDiagonal);
  rhs_ = -gradient_;
  damped_inverse_.resize(num_blocks_);
  for (int i = 0; i < num_blocks_; ++i) {
    Eigen::Matrix2d c = block_hessian_[i];
    for (int k = 0; k < 2; ++k) c(k, k) += gamma * std::max(block_hessian_[i](k, k), kMinDiagonal);
    const double det = c(0, 0) * c(1, 1) - c(0, 1) * c(1, 0);
    if (!(det > 0) || !(c(0, 0) > 0)) return false;
    Eigen::Matrix2d& inverse = damped_inverse_[i];
    inverse << c(1, 1) / det, -c(0, 1) / det, -c(1, 0) / det, c(0, 0) / det;
    // Schur term E_i C_i'^-1 E_i^T and right-hand side E_i C_i'^-1 g_i over E_i's non-zero rows.
    const Eigen::Vector2d scaled_gradient = inverse * block_gradient_[i];
    for (int a = block_begin_[i]; a < block_begin_[i + 1]; ++a) {
      const Eigen::Vector2d ea = inverse * block_coupling_[a];
      rhs_[block_columns_[a]] += block_coupling_[a].dot(scaled_gradient);
      for (int b = block_begin_[i]; b <= a; ++b) reduced_(block_columns_[a], block_columns_[b]) -= ea.dot(block_coupling_[b]);
    }
  }
  ldlt_.compute(reduced_);  // reuses its storage from the previous solve
  if (ldlt_.info() != Eigen::Success || !ldlt_.isPositive()) return false;
  d_pose = ldlt_.solve(rhs_);
  if (!d_pose.allFinite()) return false;
  d_uv.resize(num_blocks_);
  for (int i = 0; i < num_blocks_; ++i) {
    Eigen::Vector2d coupled = block_gradient_[i];
    for (int a = block_begin_[i]; a < block_begin_[i + 1]; ++a) coupled += block_coupling_[a] * d_pose[block_columns_[a]];
    d_uv[i] = -damped_inverse_[i] * coupled;
    if (!d_uv[i].allFinite()) return false;
  }
  return true;
}

double SchurSystem::predicted_decrease(double gamma, const Eigen::VectorXd& d_pose,
                                      const std::vector<Eigen::Vector2d>& d_uv) const {
  double damped = 0, linear = gradient_.dot(d_pose);
  for (int d = 0; d < num_pose_; ++d) damped += std::max(hessian_(d, d), kMinDiagonal) * d_pose[d] * d_pose[d];
  for (int i = 0; i < num_blocks_; ++i) {
    linear += block_gradient_[i].dot(d_uv[i]);
    for (int k = 0; k < 2; ++k) damped += std::max(block_hessian_[i](k, k), kMinDiagonal) * d_uv[i][k] * d_uv[i][k];
  }
  return gamma * damped - linear;
}

}  // namespace posefuse::fit
