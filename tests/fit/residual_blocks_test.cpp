// Jacobians of every energy term (paper 2, eq. 5-12) against central finite differences.
#include "fit/residual_blocks.hpp"

#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "body/template_generator.hpp"
#include "fit/camera_projection.hpp"
#include "model_frames.hpp"

namespace posefuse::fit {
namespace {

constexpr double kStep = 1e-6;

// A posed template with pose derivatives, and a second evaluator for the finite differences.
struct PosedModel {
  std::shared_ptr<const body::SmplModel> model = body::make_template(body::Sex::kMale);
  body::PoseLayout layout = body::PoseLayout::upper_body();
  body::BodyEvaluator eval{model, layout}, probe{model, layout};
  body::BodySurface surface{model->faces, model->num_vertices()}, probe_surface{model->faces, model->num_vertices()};
  Eigen::VectorXd beta = Eigen::VectorXd::Constant(10, 0.2);
  Eigen::VectorXd theta;

  PosedModel() {
    theta = testing::facing_pose(layout, 2.2, 1);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> jitter(-0.1, 0.1);
    for (int d = 3; d < layout.size(); ++d) theta[d] += jitter(rng);
    eval.evaluate(beta, theta, body::Derivatives::kPose);
    surface.update(eval.vertices());
  }
  // Poses the probe at theta + h e_d.
  void probe_at(int d, double h) {
    Eigen::VectorXd t = theta;
    t[d] += h;
    probe.evaluate(beta, t, body::Derivatives::kNone);
    probe_surface.update(probe.vertices());
  }
  // Central difference of f(probe state) along DOF d.
  template <typename F>
  Eigen::VectorXd pose_difference(int d, F&& f) {
    probe_at(d, kStep);
    const Eigen::VectorXd plus = f();
    probe_at(d, -kStep);
    const Eigen::VectorXd minus = f();
    return (plus - minus) / (2 * kStep);
  }
};

TEST(FitResidualBlocks, DataResidualPoseAndCorrespondenceJacobiansMatchFiniteDifferences) {
  PosedModel m;
  DataResidual block{{0.1, 0.2, 2.1}, Eigen::Vector3d(0.2, -0.1, -1).normalized(), 21.0, 0.25};
  std::mt19937 rng(7);
  for (int trial = 0; trial < 12; ++trial) {
    const body::SurfacePoint nu{static_cast<int>(rng() % m.model->num_faces()), 0.2 + 0.05 * (trial % 5),
                                0.15 + 0.04 * (trial % 4)};
    Vector6d r;
    Eigen::MatrixXd J(6, m.layout.size());
    Eigen::Matrix<double, 6, 2> J_uv;
    block.evaluate(m.surface, m.eval, nu, r, J, J_uv);
    EXPECT_LT((r - block.residual(m.surface, nu)).norm(), 1e-12);
    for (int d = 0; d < m.layout.size(); ++d) {
      const Eigen::VectorXd fd =
          m.pose_difference(d, [&] { return Eigen::VectorXd(block.residual(m.probe_surface, nu)); });
      ASSERT_LT((fd - J.col(d)).norm(), 1e-5 * (1 + fd.norm()))
          << "face " << nu.face << " dof " << m.layout.dof(d).name;
    }
    for (int c = 0; c < 2; ++c) {
      body::SurfacePoint plus = nu, minus = nu;
      (c == 0 ? plus.u : plus.v) += kStep;
      (c == 0 ? minus.u : minus.v) -= kStep;
      const Vector6d fd = (block.residual(m.surface, plus) - block.residual(m.surface, minus)) / (2 * kStep);
      ASSERT_LT((fd - J_uv.col(c)).norm(), 1e-5 * (1 + fd.norm())) << "uv column " << c;
    }
  }
}

TEST(FitResidualBlocks, ProjectionJacobianMatchesFiniteDifferences) {
  const raycast::DepthIntrinsics intrinsics;
  for (const Eigen::Vector3d& p :
       {Eigen::Vector3d(0.3, -0.2, 2.0), Eigen::Vector3d(-1.1, 0.8, 1.5), Eigen::Vector3d(0.01, 0.02, 0.7)}) {
    const Projection proj = project_with_jacobian(intrinsics, p);
    // Same pixel as the camera model.
    const auto pixel = raycast::DepthCamera(intrinsics).project(p);
    ASSERT_TRUE(pixel.has_value());
    EXPECT_LT((*pixel - proj.pixel).norm(), 1e-9);
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d h = kStep * Eigen::Vector3d::Unit(c);
      const Eigen::Vector2d fd =
          (project_with_jacobian(intrinsics, p + h).pixel - project_with_jacobian(intrinsics, p - h).pixel) /
          (2 * kStep);
      EXPECT_LT((fd - proj.d_pixel_d_point.col(c)).norm(), 1e-4 * (1 + fd.norm())) << "axis " << c;
    }
  }
}

TEST(FitResidualBlocks, SilhouetteResidualOfVertexAndJointMatchesFiniteDifferences) {
  PosedModel m;
  const raycast::DepthIntrinsics intrinsics;
  const SilhouetteResidual block{{250.0, 200.0}, std::sqrt(10.0 / 150)};
  Eigen::Matrix3Xd vertex_jacobian(3, m.layout.size());
  double r = 0;
  Eigen::MatrixXd J(1, m.layout.size());
  const auto as_vector = [](double value) { return Eigen::VectorXd::Constant(1, value); };
  for (int vertex : {5, 300, 777}) {  // bg: a model vertex
    vertex_jacobian.setZero();
    m.eval.add_vertex_pose_jacobian(vertex, 1.0, vertex_jacobian);
    block.evaluate(intrinsics, m.eval.vertices().col(vertex), vertex_jacobian, r, J);
    EXPECT_NEAR(r, block.residual(intrinsics, m.eval.vertices().col(vertex)), 1e-12);
    EXPECT_GT(r, 0.0);
    for (int d = 0; d < m.layout.size(); ++d) {
      const Eigen::VectorXd fd =
          m.pose_difference(d, [&] { return as_vector(block.residual(intrinsics, m.probe.vertices().col(vertex))); });
      ASSERT_LT((fd - J.col(d)).norm(), 1e-4 * (1 + fd.norm())) << "vertex " << vertex << " dof " << d;
    }
  }
  for (int joint : {body::kLeftWrist, body::kHead, body::kPelvis}) {  // bgJoint
    block.evaluate(intrinsics, m.eval.joints().col(joint), m.eval.joint_pose_jacobian().middleRows<3>(3 * joint), r, J);
    for (int d = 0; d < m.layout.size(); ++d) {
      const Eigen::VectorXd fd =
          m.pose_difference(d, [&] { return as_vector(block.residual(intrinsics, m.probe.joints().col(joint))); });
      ASSERT_LT((fd - J.col(d)).norm(), 1e-4 * (1 + fd.norm())) << "joint " << joint << " dof " << d;
    }
  }
}

TEST(FitResidualBlocks, SilhouetteResidualSeesNoDecreaseAlongTheEdgeOnlyAcrossIt) {
  // The point projects 10 px right of its target on a vertical silhouette edge. A motion that
  // moves its image down (along the edge, where the closest pixel follows it) leaves the
  // distance as it is to first order; a motion to the right changes it by the image motion.
  const raycast::DepthIntrinsics intrinsics;
  const Eigen::Vector3d x_K(0.0, 0.0, 2.0);
  const Eigen::Vector2d pixel = project_with_jacobian(intrinsics, x_K).pixel;
  const SilhouetteResidual block{pixel - Eigen::Vector2d(10.0, 0.0), 0.5};
  PoseRows3 d_x(3, 2);
  d_x.col(0) = Eigen::Vector3d(0.0, 0.01, 0.0);  // down the image (K: y down)
  d_x.col(1) = Eigen::Vector3d(0.01, 0.0, 0.0);  // to the right
  double r = 0;
  Eigen::MatrixXd J(1, 2);
  block.evaluate(intrinsics, x_K, d_x, r, J);
  EXPECT_NEAR(r, 0.5 * 10.0, 1e-9);
  EXPECT_NEAR(J(0, 0), 0.0, 1e-12);
  const Eigen::Matrix<double, 2, 3> d_pixel = project_with_jacobian(intrinsics, x_K).d_pixel_d_point;
  EXPECT_NEAR(J(0, 1), 0.5 * d_pixel(0, 0) * 0.01, 1e-12);
  EXPECT_GT(std::abs(J(0, 1)), 0.5 * 0.5 * intrinsics.fx * 0.01 / 2.0);  // about fx / z per metre
  // The offset form (q held) credits the slide along the edge with the image motion.
  Eigen::Vector2d offset;
  Eigen::MatrixXd J_offset(2, 2);
  block.evaluate_offset(intrinsics, x_K, d_x, offset, J_offset);
  EXPECT_NEAR(offset.norm(), r, 1e-12);
  EXPECT_GT(std::abs(J_offset(1, 0)), 0.5 * 0.5 * intrinsics.fy * 0.01 / 2.0);
  // On the target itself the distance has no direction: no row, not NaN.
  const SilhouetteResidual on_target{pixel, 0.5};
  on_target.evaluate(intrinsics, x_K, d_x, r, J);
  EXPECT_EQ(r, 0.0);
  EXPECT_TRUE(J.isZero(0.0));
}

TEST(FitResidualBlocks, BehindResidualMatchesFiniteDifferences) {
  PosedModel m;
  const BehindResidual block{{0.05, 0.3, 2.3}, std::sqrt(0.25 / 40)};
  Eigen::Matrix3Xd vertex_jacobian = Eigen::Matrix3Xd::Zero(3, m.layout.size());
  const int vertex = 420;
  m.eval.add_vertex_pose_jacobian(vertex, 1.0, vertex_jacobian);
  double r = 0;
  Eigen::MatrixXd J(1, m.layout.size());
  block.evaluate(m.eval.vertices().col(vertex), vertex_jacobian, r, J);
  EXPECT_NEAR(r, block.weight * (m.eval.vertices().col(vertex) - block.target_K).norm(), 1e-15);
  for (int d = 0; d < m.layout.size(); ++d) {
    const Eigen::VectorXd fd = m.pose_difference(
        d, [&] { return Eigen::VectorXd::Constant(1, block.residual(m.probe.vertices().col(vertex))); });
    ASSERT_LT((fd - J.col(d)).norm(), 1e-6 * (1 + fd.norm())) << "dof " << d;
  }
}

TEST(FitResidualBlocks, LimitResidualMatchesFiniteDifferencesAndEquation8) {
  const body::PoseLayout layout = body::PoseLayout::upper_body();
  const int size = LimitResidual::size(layout);
  EXPECT_EQ(size, layout.size() - 6);  // eq. 8 sums over N_theta - 6 DOF
  const LimitResidual block{std::sqrt(10000.0 / size)};
  // Alternate below, inside and above the range, away from the kinks.
  Eigen::VectorXd theta = layout.zero();
  for (int d = 0; d < layout.size(); ++d) {
    const body::Dof& dof = layout.dof(d);
    if (!dof.limited) continue;
    theta[d] = d % 3 == 0 ? dof.min_rad - 0.2 : d % 3 == 1 ? 0.5 * (dof.min_rad + dof.max_rad) : dof.max_rad + 0.3;
  }
  Eigen::VectorXd r(size);
  Eigen::MatrixXd J(size, layout.size());
  block.evaluate(layout, theta, r, J);
  EXPECT_NEAR(r.squaredNorm(), block.energy(layout, theta), 1e-9);
  // eq. 8 directly: lambda / (N - 6) * sum excess^2.
  double expected = 0;
  for (int d = 0; d < layout.size(); ++d) {
    const body::Dof& dof = layout.dof(d);
    if (d % 3 == 0 && dof.limited) expected += 0.2 * 0.2;
    if (d % 3 == 2 && dof.limited) expected += 0.3 * 0.3;
  }
  EXPECT_NEAR(r.squaredNorm(), 10000.0 / size * expected, 1e-6);
  for (int d = 0; d < layout.size(); ++d) {
    Eigen::VectorXd plus = theta, minus = theta, r_plus(size), r_minus(size);
    Eigen::MatrixXd unused(size, layout.size());
    plus[d] += kStep;
    minus[d] -= kStep;
    block.evaluate(layout, plus, r_plus, unused);
    block.evaluate(layout, minus, r_minus, unused);
    ASSERT_LT(((r_plus - r_minus) / (2 * kStep) - J.col(d)).norm(), 1e-5) << "dof " << d;
  }
}

TEST(FitResidualBlocks, ForearmDirectionResidualMatchesFiniteDifferences) {
  PosedModel m;
  for (bool left : {true, false}) {
    const ForearmDirectionResidual block{left ? body::kLeftElbow : body::kRightElbow,
                                         left ? body::kLeftWrist : body::kRightWrist,
                                         Eigen::Vector3d(0.3, -0.5, 0.8).normalized(), std::sqrt(15.0)};
    Eigen::Vector3d r;
    Eigen::MatrixXd J(3, m.layout.size());
    block.evaluate(m.eval.joints(), m.eval.joint_pose_jacobian(), r, J);
    // Zero residual when the expected direction is the model's own.
    const ForearmDirectionResidual matching{block.elbow, block.wrist, testing::forearm_direction(m.eval.joints(), left),
                                            1.0};
    EXPECT_LT(matching.residual(m.eval.joints()).norm(), 1e-12);
    for (int d = 0; d < m.layout.size(); ++d) {
      const Eigen::VectorXd fd =
          m.pose_difference(d, [&] { return Eigen::VectorXd(block.residual(m.probe.joints())); });
      ASSERT_LT((fd - J.col(d)).norm(), 1e-5 * (1 + fd.norm())) << "dof " << d;
    }
  }
}

}  // namespace
}  // namespace posefuse::fit
