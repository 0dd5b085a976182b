#include "fit/schur_system.hpp"

#include <Eigen/Cholesky>
#include <algorithm>

#include "common/error.hpp"

namespace posefuse::fit {

void SchurSystem::linearise(const Eigen::Ref<const Eigen::MatrixXd>& J_pose, const Eigen::Ref<const Eigen::VectorXd>& r,
                            const std::vector<UvJacobian>& J_uv, int num_blocks) {
  if (J_pose.rows() != r.size() || J_pose.rows() < 6 * num_blocks || static_cast<int>(J_uv.size()) < num_blocks)
    throw Error(ErrorCode::kInternal, "schur_system", "inconsistent residual and Jacobian sizes");
  num_pose_ = static_cast<int>(J_pose.cols());
  num_blocks_ = num_blocks;
  hessian_.setZero(num_pose_, num_pose_);
  hessian_.selfadjointView<Eigen::Lower>().rankUpdate(J_pose.transpose());
  gradient_.noalias() = J_pose.transpose() * r;
  coupling_.resize(num_pose_, 2 * num_blocks);
  block_hessian_.resize(num_blocks);
  block_gradient_.resize(num_blocks);
  for (int i = 0; i < num_blocks; ++i) {
    const auto A = J_pose.middleRows<6>(6 * i);
    const UvJacobian& B = J_uv[i];
    coupling_.middleCols<2>(2 * i).noalias() = A.transpose() * B;
    block_hessian_[i].noalias() = B.transpose() * B;
    block_gradient_[i].noalias() = B.transpose() * r.segment<6>(6 * i);
  }
}

bool SchurSystem::solve(double gamma, Eigen::VectorXd& d_pose, std::vector<Eigen::Vector2d>& d_uv) {
  reduced_ = hessian_;
  for (int d = 0; d < num_pose_; ++d) reduced_(d, d) += gamma * std::max(hessian_(d, d), kMinDiagonal);
  rhs_ = -gradient_;
  scaled_coupling_.resize(num_pose_, 2 * num_blocks_);
  damped_inverse_.resize(num_blocks_);
  for (int i = 0; i < num_blocks_; ++i) {
    Eigen::Matrix2d c = block_hessian_[i];
    for (int k = 0; k < 2; ++k) c(k, k) += gamma * std::max(block_hessian_[i](k, k), kMinDiagonal);
    // C' = L L^T: the Schur term E C'^-1 E^T = (E L^-T)(E L^-T)^T, one rank update for all blocks.
    const Eigen::LLT<Eigen::Matrix2d> llt(c);
    if (llt.info() != Eigen::Success) return false;
    const Eigen::Matrix2d l_inv = llt.matrixL().solve(Eigen::Matrix2d::Identity());
    scaled_coupling_.middleCols<2>(2 * i).noalias() = coupling_.middleCols<2>(2 * i) * l_inv.transpose();
    damped_inverse_[i].noalias() = l_inv.transpose() * l_inv;
    rhs_.noalias() += coupling_.middleCols<2>(2 * i) * (damped_inverse_[i] * block_gradient_[i]);
  }
  reduced_.selfadjointView<Eigen::Lower>().rankUpdate(scaled_coupling_, -1.0);
  const Eigen::LDLT<Eigen::MatrixXd, Eigen::Lower> ldlt(reduced_);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return false;
  d_pose = ldlt.solve(rhs_);
  if (!d_pose.allFinite()) return false;
  d_uv.resize(num_blocks_);
  for (int i = 0; i < num_blocks_; ++i)
    d_uv[i] = -damped_inverse_[i] * (block_gradient_[i] + coupling_.middleCols<2>(2 * i).transpose() * d_pose);
  return true;
}

}  // namespace posefuse::fit
