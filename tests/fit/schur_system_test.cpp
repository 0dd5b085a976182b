// The Schur-complement LM solve equals the dense solve of the full damped normal equations.
#include "fit/schur_system.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

namespace posefuse::fit {
namespace {

TEST(FitSchurSystem, EqualsDenseSolveOfTheFullDampedSystem) {
  std::mt19937 rng(11);
  std::normal_distribution<double> normal;
  const int N = 12, n = 20, extra_rows = 15;
  const int K = 6 * n + extra_rows;
  Eigen::MatrixXd J_pose(K, N);
  for (int i = 0; i < K; ++i)
    for (int j = 0; j < N; ++j) J_pose(i, j) = normal(rng);
  Eigen::VectorXd r(K);
  for (int i = 0; i < K; ++i) r[i] = normal(rng);
  std::vector<UvJacobian> J_uv(n);
  for (auto& b : J_uv)
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 2; ++j) b(i, j) = normal(rng);
  // Full Jacobian over (theta, u_1, v_1, ...).
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(K, N + 2 * n);
  J.leftCols(N) = J_pose;
  for (int i = 0; i < n; ++i) J.block(6 * i, N + 2 * i, 6, 2) = J_uv[i];
  SchurSystem system;
  system.linearise(J_pose, r, J_uv, n);
  for (double gamma : {0.0, 1e-3, 1.0, 100.0}) {
    Eigen::MatrixXd A = J.transpose() * J;
    const Eigen::VectorXd diagonal = A.diagonal();
    for (int k = 0; k < A.rows(); ++k) A(k, k) += gamma * std::max(diagonal[k], SchurSystem::kMinDiagonal);
    const Eigen::VectorXd expected = A.ldlt().solve(-J.transpose() * r);
    Eigen::VectorXd d_pose;
    std::vector<Eigen::Vector2d> d_uv;
    ASSERT_TRUE(system.solve(gamma, d_pose, d_uv));
    EXPECT_LT((d_pose - expected.head(N)).norm(), 1e-9 * (1 + expected.norm())) << "gamma " << gamma;
    for (int i = 0; i < n; ++i)
      EXPECT_LT((d_uv[i] - expected.segment<2>(N + 2 * i)).norm(), 1e-9 * (1 + expected.norm())) << "block " << i;
  }
}

}  // namespace
}  // namespace posefuse::fit
