#include "body/body_evaluator.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>

#include "common/error.hpp"
#include "random_model.hpp"

namespace posefuse::body {
namespace {

Eigen::VectorXd random_vector(int n, double scale, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-scale, scale);
  Eigen::VectorXd x(n);
  for (int i = 0; i < n; ++i) x[i] = uni(rng);
  return x;
}

struct NumericDerivative {
  Eigen::Matrix3Xd vertices, joints;
};

// Central difference of the posed vertices and joints w.r.t. entry `index` of beta (shape) or
// of theta (otherwise).
NumericDerivative central_difference(BodyEvaluator& probe, const Eigen::VectorXd& beta, const Eigen::VectorXd& theta,
                                     bool shape, int index) {
  const double h = 1e-6;
  Eigen::VectorXd beta_plus = beta, beta_minus = beta, theta_plus = theta, theta_minus = theta;
  (shape ? beta_plus : theta_plus)[index] += h;
  (shape ? beta_minus : theta_minus)[index] -= h;
  probe.evaluate(beta_plus, theta_plus, Derivatives::kNone);
  NumericDerivative out{probe.vertices(), probe.joints()};
  probe.evaluate(beta_minus, theta_minus, Derivatives::kNone);
  out.vertices = (out.vertices - probe.vertices()) / (2 * h);
  out.joints = (out.joints - probe.joints()) / (2 * h);
  return out;
}

// Central differences of every vertex and joint against the analytic pose Jacobian.
void check_pose_jacobian(const std::shared_ptr<SmplModel>& model, const PoseLayout& layout, unsigned seed) {
  BodyEvaluator eval(model, layout);
  const Eigen::VectorXd beta = random_vector(model->num_betas(), 1.0, seed);
  const Eigen::VectorXd theta = random_vector(layout.size(), 0.8, seed + 1);
  eval.evaluate(beta, theta, Derivatives::kPose);
  const int v = model->num_vertices();
  Eigen::MatrixXd analytic = Eigen::MatrixXd::Zero(3 * v, layout.size());
  for (int i = 0; i < v; ++i) {
    Eigen::Matrix3Xd block = Eigen::Matrix3Xd::Zero(3, layout.size());
    eval.add_vertex_pose_jacobian(i, 1.0, block);
    analytic.middleRows<3>(3 * i) = block;
  }
  const Eigen::MatrixXd joint_analytic = eval.joint_pose_jacobian();

  BodyEvaluator probe(model, layout);
  for (int d = 0; d < layout.size(); ++d) {
    const NumericDerivative numeric = central_difference(probe, beta, theta, false, d);
    for (int i = 0; i < v; ++i)
      ASSERT_LT((numeric.vertices.col(i) - analytic.block<3, 1>(3 * i, d)).norm(), 1e-6)
          << "vertex " << i << " dof " << layout.dof(d).name;
    for (int j = 0; j < kNumJoints; ++j)
      ASSERT_LT((numeric.joints.col(j) - joint_analytic.block<3, 1>(3 * j, d)).norm(), 1e-6)
          << "joint " << j << " dof " << layout.dof(d).name;
  }
}

TEST(BodyEvaluator, PoseJacobianMatchesFiniteDifferencesAllJoints) {
  check_pose_jacobian(testing::random_model(3, 10, false, 1), PoseLayout::all_joints(), 10);
}

TEST(BodyEvaluator, PoseJacobianMatchesFiniteDifferencesWithPosedirs) {
  check_pose_jacobian(testing::random_model(2, 10, true, 2), PoseLayout::all_joints(), 20);
}

TEST(BodyEvaluator, PoseJacobianMatchesFiniteDifferencesUpperAndFullBody) {
  check_pose_jacobian(testing::random_model(3, 10, false, 3), PoseLayout::upper_body(), 30);
  check_pose_jacobian(testing::random_model(3, 10, false, 4), PoseLayout::full_body(), 40);
}

TEST(BodyEvaluator, PoseJacobiansOnRequestEqualTheFullEvaluation) {
  for (bool posedirs : {false, true}) {
    auto model = testing::random_model(3, 10, posedirs, 7);
    const PoseLayout layout = PoseLayout::upper_body();
    BodyEvaluator full(model, layout), on_request(model, layout);
    const Eigen::VectorXd beta = random_vector(10, 1.0, 70);
    Eigen::VectorXd theta = random_vector(layout.size(), 0.8, 71);
    on_request.evaluate(beta, theta, Derivatives::kPose);  // stale values from another pose
    theta[7] += 0.3;
    full.evaluate(beta, theta, Derivatives::kPose);
    on_request.evaluate(beta, theta, Derivatives::kPoseOnRequest);
    EXPECT_EQ(on_request.vertices(), full.vertices());
    EXPECT_EQ(on_request.joint_pose_jacobian(), full.joint_pose_jacobian());
    std::vector<int> some;
    for (int i = 1; i < model->num_vertices(); i += 3) some.push_back(i);
    on_request.compute_vertex_pose_jacobians(some);
    for (int i : some) {
      ASSERT_TRUE(std::ranges::equal(on_request.vertex_dofs(i), full.vertex_dofs(i)));
      ASSERT_EQ(on_request.vertex_pose_jacobian(i), full.vertex_pose_jacobian(i)) << "vertex " << i;
    }
    const std::vector<int> out_of_range = {model->num_vertices()};
    EXPECT_THROW(on_request.compute_vertex_pose_jacobians(out_of_range), Error);
  }
}

TEST(BodyEvaluator, ShapeJacobianMatchesFiniteDifferences) {
  for (bool posedirs : {false, true}) {
    auto model = testing::random_model(2, 10, posedirs, 5);
    const PoseLayout layout = PoseLayout::all_joints();
    BodyEvaluator eval(model, layout);
    const Eigen::VectorXd beta = random_vector(10, 1.0, 50);
    const Eigen::VectorXd theta = random_vector(layout.size(), 0.8, 51);
    eval.evaluate(beta, theta, Derivatives::kPoseAndShape);
    BodyEvaluator probe(model, layout);
    for (int b = 0; b < 10; ++b) {
      const NumericDerivative numeric = central_difference(probe, beta, theta, true, b);
      for (int i = 0; i < model->num_vertices(); ++i)
        ASSERT_LT((numeric.vertices.col(i) - eval.vertex_shape_jacobian(i).col(b)).norm(), 1e-6)
            << "vertex " << i << " beta " << b;
      for (int j = 0; j < kNumJoints; ++j)
        ASSERT_LT((numeric.joints.col(j) - eval.joint_shape_jacobian().block<3, 1>(3 * j, b)).norm(), 1e-6)
            << "joint " << j << " beta " << b;
    }
  }
}

TEST(BodyEvaluator, ZeroPoseReproducesShapedTemplate) {
  auto model = testing::random_model(2, 10, true, 6);
  BodyEvaluator eval(model, PoseLayout::upper_body());
  const Eigen::VectorXd beta = random_vector(10, 1.0, 60);
  eval.evaluate(beta, PoseLayout::upper_body().zero(), Derivatives::kNone);
  Eigen::VectorXd shaped =
      Eigen::Map<const Eigen::VectorXd>(model->v_template.data(), model->v_template.size()) + model->shapedirs * beta;
  EXPECT_LT((Eigen::Map<const Eigen::VectorXd>(eval.vertices().data(), shaped.size()) - shaped).cwiseAbs().maxCoeff(),
            1e-12);
}

TEST(BodyEvaluator, VertexDependsOnlyOnAncestorDofs) {
  auto model = testing::random_model(2, 10, false, 7);
  const PoseLayout layout = PoseLayout::upper_body();
  BodyEvaluator eval(model, layout);
  // Vertex 0 is skinned to joints 0, 5, 11: the left collar's DOFs must not be in its list.
  for (int d : eval.vertex_dofs(0)) EXPECT_NE(layout.dof(d).joint, kLeftCollar);
  EXPECT_LT(static_cast<int>(eval.vertex_dofs(0).size()), layout.size());
}

TEST(BodyEvaluator, RejectsBadInput) {
  auto model = testing::random_model(2, 10, false, 8);
  const PoseLayout layout = PoseLayout::upper_body();
  BodyEvaluator eval(model, layout);
  Eigen::VectorXd theta = layout.zero();
  EXPECT_THROW(eval.evaluate(Eigen::VectorXd::Zero(11), theta, Derivatives::kNone), Error);
  EXPECT_THROW(eval.evaluate(Eigen::VectorXd::Zero(10), Eigen::VectorXd::Zero(39), Derivatives::kNone), Error);
  theta[7] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(eval.evaluate(Eigen::VectorXd::Zero(10), theta, Derivatives::kNone), Error);
  auto broken = std::make_shared<SmplModel>(*model);
  broken->faces(1, 3) = 100000;
  EXPECT_THROW(BodyEvaluator(broken, layout), Error);
  broken = std::make_shared<SmplModel>(*model);
  broken->parents[5] = 3;
  EXPECT_THROW(BodyEvaluator(broken, layout), Error);
}

TEST(PoseLayout, DofCountsMatchPaper2) {
  EXPECT_EQ(PoseLayout::upper_body().size(), 40);
  EXPECT_EQ(PoseLayout::full_body().size(), 48);
  int limited = 0;
  const PoseLayout full = PoseLayout::full_body();
  for (const Dof& d : full.dofs()) {
    if (d.limited) {
      ++limited;
      EXPECT_LT(d.min_rad, d.max_rad) << d.name;
    }
  }
  EXPECT_EQ(limited, 48 - 6);
  // Roll about the bone is removed at the arm joints (bone along x in the T-pose).
  const PoseLayout upper = PoseLayout::upper_body();
  EXPECT_THROW(upper.index_of("left_elbow_x"), Error);
  EXPECT_NO_THROW(upper.index_of("spine2_y"));
}

// The body tracker fits frames with straight legs in the upper body and keeps full-body poses: the
// full body's first 40 DOFs are the upper body's, and the 8 after them are the knees and ankles.
TEST(PoseLayout, TheFullBodyIsTheUpperBodyThenTheKneesAndAnkles) {
  const PoseLayout upper = PoseLayout::upper_body(), full = PoseLayout::full_body();
  for (int d = 0; d < upper.size(); ++d) {
    EXPECT_EQ(full.dof(d).name, upper.dof(d).name) << d;
    EXPECT_EQ(full.dof(d).min_rad, upper.dof(d).min_rad) << d;
    EXPECT_EQ(full.dof(d).max_rad, upper.dof(d).max_rad) << d;
  }
  for (int d = upper.size(); d < full.size(); ++d) {
    const int joint = full.dof(d).joint;
    EXPECT_TRUE(joint == kLeftKnee || joint == kRightKnee || joint == kLeftAnkle || joint == kRightAnkle)
        << full.dof(d).name;
  }
}

}  // namespace
}  // namespace posefuse::body
