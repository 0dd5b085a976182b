// The Schur-complement LM solve equals the dense solve of the full damped normal equations.
#include "fit/schur_system.hpp"

#include "common/error.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

namespace posefuse::fit {
namespace {

// Random normal equations: N pose DOF, n correspondence blocks and extra pose-only rows.
struct RandomProblem {
  int N, n;
  Eigen::MatrixXd J_pose;
  Eigen::VectorXd r;
  std::vector<UvJacobian> J_uv;

  RandomProblem(unsigned seed, int num_pose, int num_blocks, int extra_rows)
      : N(num_pose), n(num_blocks), J_pose(6 * num_blocks + extra_rows, num_pose), r(J_pose.rows()), J_uv(num_blocks) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> normal;
    for (int i = 0; i < J_pose.rows(); ++i)
      for (int j = 0; j < N; ++j) J_pose(i, j) = normal(rng);
    for (int i = 0; i < r.size(); ++i) r[i] = normal(rng);
    for (auto& b : J_uv)
      for (int i = 0; i < 6; ++i)
        for (int j = 0; j < 2; ++j) b(i, j) = normal(rng);
  }

  // The full Jacobian over (the pose DOFs `columns`, u_1, v_1, ...) and its damped LM step.
  Eigen::VectorXd dense_step(const std::vector<int>& columns, double gamma) const {
    const int F = static_cast<int>(columns.size());
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(J_pose.rows(), F + 2 * n);
    for (int c = 0; c < F; ++c) J.col(c) = J_pose.col(columns[c]);
    for (int i = 0; i < n; ++i) J.block(6 * i, F + 2 * i, 6, 2) = J_uv[i];
    Eigen::MatrixXd A = J.transpose() * J;
    const Eigen::VectorXd diagonal = A.diagonal();
    for (int k = 0; k < A.rows(); ++k) A(k, k) += gamma * std::max(diagonal[k], SchurSystem::kMinDiagonal);
    return A.ldlt().solve(-J.transpose() * r);
  }
};

TEST(FitSchurSystem, EqualsDenseSolveOfTheFullDampedSystem) {
  const RandomProblem p(11, 12, 20, 15);
  std::vector<int> all(p.N);
  for (int d = 0; d < p.N; ++d) all[d] = d;
  SchurSystem system;
  system.linearise(p.J_pose, p.r, p.J_uv, p.n);
  for (double gamma : {0.0, 1e-3, 1.0, 100.0}) {
    const Eigen::VectorXd expected = p.dense_step(all, gamma);
    Eigen::VectorXd d_pose;
    std::vector<Eigen::Vector2d> d_uv;
    ASSERT_TRUE(system.solve(gamma, d_pose, d_uv));
    EXPECT_LT((d_pose - expected.head(p.N)).norm(), 1e-9 * (1 + expected.norm())) << "gamma " << gamma;
    for (int i = 0; i < p.n; ++i)
      EXPECT_LT((d_uv[i] - expected.segment<2>(p.N + 2 * i)).norm(), 1e-9 * (1 + expected.norm())) << "block " << i;
  }
}

TEST(FitSchurSystem, HeldDofsEqualTheSolveWithoutTheirColumns) {
  const RandomProblem p(12, 10, 15, 12);
  const std::vector<int> held = {2, 7, 9}, free = {0, 1, 3, 4, 5, 6, 8};
  const int F = static_cast<int>(free.size());
  SchurSystem system;
  system.linearise(p.J_pose, p.r, p.J_uv, p.n);
  for (double gamma : {1e-3, 1.0}) {
    const Eigen::VectorXd expected = p.dense_step(free, gamma);
    Eigen::VectorXd d_pose;
    std::vector<Eigen::Vector2d> d_uv;
    ASSERT_TRUE(system.solve(gamma, d_pose, d_uv, held));
    for (int d : held) EXPECT_EQ(d_pose[d], 0.0) << "held DOF " << d;
    for (int c = 0; c < F; ++c)
      EXPECT_NEAR(d_pose[free[c]], expected[c], 1e-9 * (1 + expected.norm()))
          << "gamma " << gamma << " DOF " << free[c];
    for (int i = 0; i < p.n; ++i)
      EXPECT_LT((d_uv[i] - expected.segment<2>(F + 2 * i)).norm(), 1e-9 * (1 + expected.norm())) << "block " << i;
  }
}

TEST(FitSchurSystem, PackedBlocksEqualDenseBlocks) {
  // Blocks whose pose Jacobian has zero columns, given densely (the system finds the non-zero
  // columns) and packed over a column list that also names some zero columns (as
  // SurfacePoseJacobians::face_columns may): the same normal equations and steps.
  std::mt19937 rng(12);
  std::normal_distribution<double> normal;
  const int N = 40, n = 30;
  SchurSystem dense, packed;
  dense.reset(N, n);
  packed.reset(N, n);
  for (int i = 0; i < n; ++i) {
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(6, N);
    std::vector<int> columns;
    for (int c = 0; c < N; ++c) {
      const unsigned kind = rng() % 3;  // 0: not listed, 1: listed and zero, 2: listed, non-zero
      if (kind == 0) continue;
      columns.push_back(c);
      if (kind == 2)
        for (int k = 0; k < 6; ++k) A(k, c) = normal(rng);
    }
    Eigen::MatrixXd A_packed(6, static_cast<Eigen::Index>(columns.size()));
    for (size_t c = 0; c < columns.size(); ++c) A_packed.col(static_cast<Eigen::Index>(c)) = A.col(columns[c]);
    UvJacobian B;
    Eigen::Matrix<double, 6, 1> r;
    for (int k = 0; k < 6; ++k) {
      B(k, 0) = normal(rng);
      B(k, 1) = normal(rng);
      r[k] = normal(rng);
    }
    dense.add_block(i, A, B, r);
    packed.add_block(i, columns, A_packed, B, r);
  }
  Eigen::MatrixXd J_rows(5, N);
  for (int k = 0; k < J_rows.size(); ++k) J_rows.data()[k] = normal(rng);
  const Eigen::VectorXd r_rows = Eigen::VectorXd::Constant(5, 0.5);
  dense.add_pose_rows(J_rows, r_rows);
  packed.add_pose_rows(J_rows, r_rows);
  for (double gamma : {1e-3, 1.0}) {
    Eigen::VectorXd d_dense, d_packed;
    std::vector<Eigen::Vector2d> uv_dense, uv_packed;
    ASSERT_TRUE(dense.solve(gamma, d_dense, uv_dense));
    ASSERT_TRUE(packed.solve(gamma, d_packed, uv_packed));
    EXPECT_LT((d_packed - d_dense).norm(), 1e-12 * (1 + d_dense.norm())) << "gamma " << gamma;
    for (int i = 0; i < n; ++i) EXPECT_LT((uv_packed[i] - uv_dense[i]).norm(), 1e-12 * (1 + uv_dense[i].norm()));
    EXPECT_NEAR(packed.predicted_decrease(gamma, d_packed, uv_packed),
                dense.predicted_decrease(gamma, d_dense, uv_dense),
                1e-12 * std::abs(dense.predicted_decrease(gamma, d_dense, uv_dense)));
  }
}

TEST(FitSchurSystem, RejectsPackedColumnsThatAreNotAscending) {
  SchurSystem system;
  system.reset(10, 1);
  const std::vector<int> columns = {3, 2};
  EXPECT_THROW(system.add_block(0, columns, Eigen::MatrixXd::Ones(6, 2), UvJacobian::Ones(),
                                Eigen::Matrix<double, 6, 1>::Ones()),
               Error);
}

}  // namespace
}  // namespace posefuse::fit
