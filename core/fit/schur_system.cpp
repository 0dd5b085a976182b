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
  coupling_u_.clear();
  coupling_v_.clear();
  block_jacobian_.clear();
  data_diagonal_.setZero(num_pose_);
  block_hessian_.resize(num_blocks);
  block_gradient_.resize(num_blocks);
}

void SchurSystem::add_block(int i, const Eigen::Ref<const Eigen::MatrixXd>& A, const UvJacobian& B,
                            const Eigen::Ref<const Eigen::Matrix<double, 6, 1>>& r) {
  if (A.rows() != 6 || A.cols() != num_pose_)
    throw Error(ErrorCode::kInternal, "schur_system", "Jacobian of the wrong size");
  // Gather the non-zero columns; fixed-capacity matrices keep this free of allocation.
  std::array<int, kMaxPose> columns;
  int m = 0;
  for (int c = 0; c < num_pose_; ++c)
    if (!A.col(c).isZero(0.0)) columns[m++] = c;
  Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, kMaxPose> packed(6, m);
  for (int k = 0; k < m; ++k) packed.col(k) = A.col(columns[k]);
  add_block(i, std::span<const int>(columns.data(), static_cast<size_t>(m)), packed, B, r);
}

void SchurSystem::add_block(int i, std::span<const int> columns, const Eigen::Ref<const Eigen::MatrixXd>& A,
                            const UvJacobian& B, const Eigen::Ref<const Eigen::Matrix<double, 6, 1>>& r) {
  const int m = static_cast<int>(columns.size());
  if (i < 0 || i >= num_blocks_ || A.rows() != 6 || A.cols() != m || m > num_pose_ ||
      block_begin_[i] != static_cast<int>(block_columns_.size()))
    throw Error(ErrorCode::kInternal, "schur_system", "blocks out of order or Jacobian of the wrong size");
  for (int k = 0; k < m; ++k)
    if (columns[k] < (k > 0 ? columns[k - 1] + 1 : 0) || columns[k] >= num_pose_)
      throw Error(ErrorCode::kInternal, "schur_system", "block columns not ascending or out of range");
  // A_i^T A_i enters the reduced system in solve(), together with the Schur term (one pass over
  // the pairs of columns); here only its diagonal (for the damping) and the packed columns.
  for (int a = 0; a < m; ++a) {
    const int row = columns[a];
    const Eigen::Matrix<double, 6, 1> column = A.col(a);
    gradient_[row] += column.dot(r);
    data_diagonal_[row] += column.squaredNorm();
    block_columns_.push_back(row);
    block_jacobian_.insert(block_jacobian_.end(), column.data(), column.data() + 6);
    const Eigen::Vector2d coupling = B.transpose() * column;
    coupling_u_.push_back(coupling.x());
    coupling_v_.push_back(coupling.y());
  }
  block_begin_[i + 1] = static_cast<int>(block_columns_.size());
  block_hessian_[i].noalias() = B.transpose() * B;
  block_gradient_[i].noalias() = B.transpose() * r;
}

void SchurSystem::add_pose_rows(const Eigen::Ref<const Eigen::MatrixXd>& J,
                                const Eigen::Ref<const Eigen::VectorXd>& r) {
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

bool SchurSystem::solve(double gamma, Eigen::VectorXd& d_pose, std::vector<Eigen::Vector2d>& d_uv,
                        std::span<const int> held) {
  reduced_ = hessian_;
  for (int d = 0; d < num_pose_; ++d) reduced_(d, d) += gamma * std::max(diagonal(d), kMinDiagonal);
  rhs_ = -gradient_;
  damped_inverse_.resize(num_blocks_);
  for (int i = 0; i < num_blocks_; ++i) {
    Eigen::Matrix2d c = block_hessian_[i];
    for (int k = 0; k < 2; ++k) c(k, k) += gamma * std::max(block_hessian_[i](k, k), kMinDiagonal);
    const double det = c(0, 0) * c(1, 1) - c(0, 1) * c(1, 0);
    if (!(det > 0) || !(c(0, 0) > 0)) return false;
    Eigen::Matrix2d& inverse = damped_inverse_[i];
    inverse << c(1, 1) / det, -c(0, 1) / det, -c(1, 0) / det, c(0, 0) / det;
    // A_i^T A_i - E_i C_i'^-1 E_i^T and the right-hand side's E_i C_i'^-1 g_i over the block's
    // columns (lower triangle).
    const Eigen::Vector2d scaled_gradient = inverse * block_gradient_[i];
    const int begin = block_begin_[i], end = block_begin_[i + 1];
    const double* u = coupling_u_.data() + begin;
    const double* v = coupling_v_.data() + begin;
    const double* jacobian = block_jacobian_.data() + 6 * static_cast<size_t>(begin);
    const int* columns = block_columns_.data() + begin;
    for (int a = 0; a < end - begin; ++a) {
      const double ea_u = inverse(0, 0) * u[a] + inverse(0, 1) * v[a],
                   ea_v = inverse(1, 0) * u[a] + inverse(1, 1) * v[a];
      rhs_[columns[a]] += u[a] * scaled_gradient.x() + v[a] * scaled_gradient.y();
      const Eigen::Map<const Eigen::Matrix<double, 6, 1>> column_a(jacobian + 6 * a);
      for (int b = 0; b <= a; ++b) {
        const Eigen::Map<const Eigen::Matrix<double, 6, 1>> column_b(jacobian + 6 * b);
        reduced_(columns[a], columns[b]) += column_a.dot(column_b) - (ea_u * u[b] + ea_v * v[b]);
      }
    }
  }
  if (held.empty()) {
    ldlt_.compute(reduced_);  // reuses its storage from the previous solve
    if (ldlt_.info() != Eigen::Success || !ldlt_.isPositive()) return false;
    d_pose = ldlt_.solve(rhs_);
  } else {
    // The system over the free DOFs alone, in their order: the same matrix, entry for entry, as a
    // layout without the held DOFs would build (their step is 0).
    free_.clear();
    auto next_held = held.begin();
    for (int d = 0; d < num_pose_; ++d) {
      if (next_held != held.end() && *next_held == d) ++next_held;
      else free_.push_back(d);
    }
    free_system_ = reduced_(free_, free_);
    ldlt_.compute(free_system_);
    if (ldlt_.info() != Eigen::Success || !ldlt_.isPositive()) return false;
    free_rhs_ = rhs_(free_);
    free_step_ = ldlt_.solve(free_rhs_);
    d_pose.setZero(num_pose_);
    d_pose(free_) = free_step_;
  }
  if (!d_pose.allFinite()) return false;
  d_uv.resize(num_blocks_);
  for (int i = 0; i < num_blocks_; ++i) {
    Eigen::Vector2d coupled = block_gradient_[i];
    for (int a = block_begin_[i]; a < block_begin_[i + 1]; ++a)
      coupled += Eigen::Vector2d(coupling_u_[a], coupling_v_[a]) * d_pose[block_columns_[a]];
    d_uv[i] = -damped_inverse_[i] * coupled;
    if (!d_uv[i].allFinite()) return false;
  }
  return true;
}

double SchurSystem::predicted_decrease(double gamma, const Eigen::VectorXd& d_pose,
                                       const std::vector<Eigen::Vector2d>& d_uv) const {
  double damped = 0, linear = gradient_.dot(d_pose);
  for (int d = 0; d < num_pose_; ++d) damped += std::max(diagonal(d), kMinDiagonal) * d_pose[d] * d_pose[d];
  for (int i = 0; i < num_blocks_; ++i) {
    linear += block_gradient_[i].dot(d_uv[i]);
    for (int k = 0; k < 2; ++k) damped += std::max(block_hessian_[i](k, k), kMinDiagonal) * d_uv[i][k] * d_uv[i][k];
  }
  return gamma * damped - linear;
}

}  // namespace posefuse::fit
