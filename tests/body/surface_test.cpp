#include "body/surface.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <numbers>
#include <random>

#include "body/mesh_topology.hpp"
#include "body/surface_pose_jacobians.hpp"
#include "body/template_generator.hpp"

namespace posefuse::body {
namespace {

// (du, dv) of face f that moves its point by the in-plane vector d.
Eigen::Vector2d uv_step(const BodySurface& s, const Eigen::Matrix3Xd& vertices, int f, const Eigen::Vector3d& d) {
  Eigen::Matrix<double, 3, 2> e;
  e.col(0) = vertices.col(s.faces()(0, f)) - vertices.col(s.faces()(2, f));
  e.col(1) = vertices.col(s.faces()(1, f)) - vertices.col(s.faces()(2, f));
  return e.colPivHouseholderQr().solve(d);
}

TEST(BodySurface, PoseJacobiansOfPositionAndNormalMatchFiniteDifferences) {
  const auto model = make_template(Sex::kFemale);
  const PoseLayout layout = PoseLayout::upper_body();
  BodyEvaluator eval(model, layout), probe(model, layout);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uni(-0.5, 0.5);
  Eigen::VectorXd theta(layout.size());
  for (int d = 0; d < layout.size(); ++d) theta[d] = uni(rng);
  const Eigen::VectorXd beta = Eigen::VectorXd::Constant(10, 0.5);
  eval.evaluate(beta, theta, Derivatives::kPose);
  BodySurface surface(model->faces, model->num_vertices()), moved(model->faces, model->num_vertices());
  surface.update(eval.vertices());
  for (int trial = 0; trial < 25; ++trial) {
    const SurfacePoint s{static_cast<int>(rng() % model->num_faces()), 0.2 + 0.3 * (uni(rng) + 0.5),
                         0.1 + 0.3 * (uni(rng) + 0.5)};
    Eigen::Matrix3Xd jp = Eigen::Matrix3Xd::Zero(3, layout.size()), jn = jp;
    surface.position_pose_jacobian(s, eval, jp);
    surface.normal_pose_jacobian(s, eval, jn);
    const double h = 1e-6;
    for (int d = 0; d < layout.size(); ++d) {
      Eigen::VectorXd plus = theta, minus = theta;
      plus[d] += h;
      minus[d] -= h;
      probe.evaluate(beta, plus, Derivatives::kNone);
      moved.update(probe.vertices());
      const Eigen::Vector3d p_plus = moved.position(s), n_plus = moved.normal(s);
      probe.evaluate(beta, minus, Derivatives::kNone);
      moved.update(probe.vertices());
      const Eigen::Vector3d p_minus = moved.position(s), n_minus = moved.normal(s);
      ASSERT_LT(((p_plus - p_minus) / (2 * h) - jp.col(d)).norm(), 1e-6) << "face " << s.face << " dof " << d;
      ASSERT_LT(((n_plus - n_minus) / (2 * h) - jn.col(d)).norm(), 1e-5) << "face " << s.face << " dof " << d;
    }
    // u, v derivatives.
    const auto ju = surface.position_uv_jacobian(s);
    const auto jnu = surface.normal_uv_jacobian(s);
    for (int c = 0; c < 2; ++c) {
      SurfacePoint a = s, b = s;
      (c == 0 ? a.u : a.v) += h;
      (c == 0 ? b.u : b.v) -= h;
      EXPECT_LT(((surface.position(a) - surface.position(b)) / (2 * h) - ju.col(c)).norm(), 1e-7);
      EXPECT_LT(((surface.normal(a) - surface.normal(b)) / (2 * h) - jnu.col(c)).norm(), 1e-6);
    }
  }
}

// A pose with every DOF uniform in [-0.5, 0.5].
Eigen::VectorXd random_pose(const PoseLayout& layout, std::mt19937& rng) {
  std::uniform_real_distribution<double> uni(-0.5, 0.5);
  Eigen::VectorXd theta(layout.size());
  for (int d = 0; d < layout.size(); ++d) theta[d] = uni(rng);
  return theta;
}

TEST(SurfacePoseJacobians, EqualTheDirectJacobiansForSamplesSharingVertices) {
  const auto model = make_template(Sex::kMale);
  const PoseLayout layout = PoseLayout::upper_body();
  BodyEvaluator eval(model, layout);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uni(-0.5, 0.5);
  Eigen::VectorXd theta = random_pose(layout, rng);
  eval.evaluate(Eigen::VectorXd::Constant(10, 0.3), theta, Derivatives::kPose);
  BodySurface surface(model->faces, model->num_vertices());
  surface.update(eval.vertices());
  SurfacePoseJacobians cached;
  const int n = layout.size();
  for (int round = 0; round < 2; ++round) {  // the second round checks that reset() forgets
    cached.reset(surface, eval);
    for (int trial = 0; trial < 60; ++trial) {
      // Neighbouring faces (shared corners) and repeats of one face at different (u, v).
      const int face = trial < 30 ? 100 + trial % 12 : static_cast<int>(rng() % model->num_faces());
      const SurfacePoint s{face, 0.1 + 0.4 * (uni(rng) + 0.5), 0.1 + 0.4 * (uni(rng) + 0.5)};
      Eigen::Matrix3Xd jp = Eigen::Matrix3Xd::Zero(3, n), jn = jp, cp(3, n), cn(3, n);
      surface.position_pose_jacobian(s, eval, jp);
      surface.normal_pose_jacobian(s, eval, jn);
      cached.evaluate(surface, eval, s, cp, cn);
      ASSERT_LT((cp - jp).cwiseAbs().maxCoeff(), 1e-12 * (1 + jp.cwiseAbs().maxCoeff())) << "face " << face;
      ASSERT_LT((cn - jn).cwiseAbs().maxCoeff(), 1e-12 * (1 + jn.cwiseAbs().maxCoeff())) << "face " << face;
    }
    theta[7] += 0.2;  // a new pose for the next round
    eval.evaluate(Eigen::VectorXd::Constant(10, 0.3), theta, Derivatives::kPose);
    surface.update(eval.vertices());
  }
}

TEST(SurfacePoseJacobians, PackedColumnsHoldEveryNonZeroColumn) {
  // face_columns(f) lists every DOF whose column of the direct Jacobians is non-zero on face f;
  // evaluate_packed gives those columns (to 1e-12), in order.
  const auto model = make_template(Sex::kMale);
  const PoseLayout layout = PoseLayout::upper_body();
  BodyEvaluator eval(model, layout);
  std::mt19937 rng(6);
  eval.evaluate(Eigen::VectorXd::Constant(10, -0.2), random_pose(layout, rng), Derivatives::kPose);
  BodySurface surface(model->faces, model->num_vertices());
  surface.update(eval.vertices());
  SurfacePoseJacobians cached;
  cached.reset(surface, eval);
  const int n = layout.size();
  int fewer = 0;
  for (int face = 0; face < model->num_faces(); face += 7) {
    const SurfacePoint s{face, 0.2, 0.5};
    Eigen::Matrix3Xd jp = Eigen::Matrix3Xd::Zero(3, n), jn = jp;
    surface.position_pose_jacobian(s, eval, jp);
    surface.normal_pose_jacobian(s, eval, jn);
    const auto columns = cached.face_columns(face);
    const Eigen::Index m = static_cast<Eigen::Index>(columns.size());
    Eigen::Matrix3Xd pp(3, m), pn(3, m);
    cached.evaluate_packed(surface, eval, s, pp, pn);
    std::vector<bool> listed(static_cast<size_t>(n), false);
    for (Eigen::Index c = 0; c < m; ++c) {
      const int d = columns[static_cast<size_t>(c)];
      ASSERT_TRUE(c == 0 || d > columns[static_cast<size_t>(c) - 1]) << "face " << face;
      listed[static_cast<size_t>(d)] = true;
      ASSERT_LT((pp.col(c) - jp.col(d)).cwiseAbs().maxCoeff(), 1e-12 * (1 + jp.cwiseAbs().maxCoeff()))
          << "face " << face;
      ASSERT_LT((pn.col(c) - jn.col(d)).cwiseAbs().maxCoeff(), 1e-12 * (1 + jn.cwiseAbs().maxCoeff()))
          << "face " << face;
    }
    for (int d = 0; d < n; ++d)
      if (!listed[static_cast<size_t>(d)]) {
        ASSERT_TRUE(jp.col(d).isZero(0.0) && jn.col(d).isZero(0.0)) << "face " << face << " DOF " << d;
      }
    fewer += m < n;
  }
  EXPECT_GT(fewer, 0);  // the lists are sparse somewhere (else the test would prove little)
}

TEST(SurfacePoseJacobians, NeedOnlyTheRingsTheyNameWithJacobiansOnRequest) {
  // An evaluator with kPoseOnRequest whose vertex Jacobians are computed only for the corners of
  // the sampled faces and the 1-rings that normal_needs_ring() names gives the direct Jacobians of
  // one with every vertex's (kPose). The on-request evaluator's other vertices hold
  // Jacobians of another pose, so a ring wrongly left out would show.
  const auto model = make_template(Sex::kMale);
  const PoseLayout layout = PoseLayout::upper_body();
  std::mt19937 rng(7);
  const Eigen::VectorXd beta = Eigen::VectorXd::Constant(10, 0.1);
  const Eigen::VectorXd theta = random_pose(layout, rng);
  BodyEvaluator full(model, layout), on_request(model, layout);
  full.evaluate(beta, theta, Derivatives::kPose);
  on_request.evaluate(beta, random_pose(layout, rng), Derivatives::kPose);  // stale Jacobians
  on_request.evaluate(beta, theta, Derivatives::kPoseOnRequest);
  BodySurface surface(model->faces, model->num_vertices());
  surface.update(full.vertices());
  SurfacePoseJacobians cached;
  cached.reset(surface, on_request);
  std::vector<int> faces, used;
  std::vector<bool> in_use(static_cast<size_t>(model->num_vertices()), false);
  const auto use = [&](int v) {
    if (!in_use[static_cast<size_t>(v)]) used.push_back(v);
    in_use[static_cast<size_t>(v)] = true;
  };
  int without_ring = 0;
  for (int face = 0; face < model->num_faces(); face += 11) {
    faces.push_back(face);
    for (int k = 0; k < 3; ++k) {
      const int v = surface.faces()(k, face);
      use(v);
      if (!cached.normal_needs_ring(v)) {
        ++without_ring;
        continue;
      }
      for (int f : surface.faces_of_vertex(v))
        for (int corner = 0; corner < 3; ++corner) use(surface.faces()(corner, f));
    }
  }
  on_request.compute_vertex_pose_jacobians(used);
  for (int face : faces) {
    const SurfacePoint s{face, 0.3, 0.4};
    const Eigen::Index n = layout.size();
    Eigen::Matrix3Xd ep = Eigen::Matrix3Xd::Zero(3, n), en = ep, cp(3, n), cn(3, n);
    surface.position_pose_jacobian(s, full, ep);
    surface.normal_pose_jacobian(s, full, en);
    cached.evaluate(surface, on_request, s, cp, cn);
    ASSERT_LT((cp - ep).cwiseAbs().maxCoeff(), 1e-12 * (1 + ep.cwiseAbs().maxCoeff())) << "face " << face;
    ASSERT_LT((cn - en).cwiseAbs().maxCoeff(), 1e-12 * (1 + en.cwiseAbs().maxCoeff())) << "face " << face;
  }
  EXPECT_GT(without_ring, 0);  // some corners skip their ring (else the test would prove little)
}

TEST(BodySurface, AdjacencyOfTheTemplateIsSymmetricAndComplete) {
  const auto model = make_template(Sex::kMale);
  BodySurface surface(model->faces, model->num_vertices());
  const auto& adj = surface.adjacency();
  for (int f = 0; f < model->num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int g = adj(k, f);
      ASSERT_GE(g, 0);
      EXPECT_TRUE(adj(0, g) == f || adj(1, g) == f || adj(2, g) == f);
    }
}

TEST(BodySurface, VertexNormalsPointOutOfTheBody) {
  const auto model = make_template(Sex::kMale);
  BodySurface surface(model->faces, model->num_vertices());
  surface.update(model->v_template);
  // Moving a little along the normal leaves the closed mesh: the signed volume grows.
  Eigen::Matrix3Xd inflated = model->v_template + 0.002 * surface.vertex_normals();
  EXPECT_GT(signed_volume(inflated, model->faces), signed_volume(model->v_template, model->faces));
  const SurfacePoint s{10, 0.3, 0.3};
  EXPECT_NEAR(surface.normal(s).norm(), 1.0, 1e-12);
}

TEST(BodySurface, WalkOnAPlaneIsAStraightLine) {
  constexpr int n = 20;
  Eigen::Matrix3Xd vertices(3, (n + 1) * (n + 1));
  for (int r = 0; r <= n; ++r)
    for (int c = 0; c <= n; ++c) vertices.col(r * (n + 1) + c) = Eigen::Vector3d(0.1 * c, 0.1 * r, 0);
  Eigen::Matrix3Xi faces(3, 2 * n * n);
  for (int r = 0, f = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const int a = r * (n + 1) + c;
      faces.col(f++) = Eigen::Vector3i(a, a + 1, a + n + 2);
      faces.col(f++) = Eigen::Vector3i(a, a + n + 2, a + n + 1);
    }
  BodySurface surface(faces, static_cast<int>(vertices.cols()));
  surface.update(vertices);
  const SurfacePoint start{2 * (3 * n + 2), 0.2, 0.5};
  const Eigen::Vector3d d(1.23, 0.77, 0);
  const Eigen::Vector2d uv = uv_step(surface, vertices, start.face, d);
  const WalkResult walk = surface.walk(start, uv[0], uv[1]);
  EXPECT_GT(walk.faces_crossed, 20);
  EXPECT_NEAR(walk.walked_m, d.norm(), 1e-12);
  EXPECT_LT((surface.position(walk.end) - (surface.position(start) + d)).norm(), 1e-12);
}

// Walking once around a prism, perpendicular to its axis, unfolds the prism exactly: the walk
// returns to its start after one perimeter and keeps going straight along the ring.
TEST(BodySurface, WalkAroundAPrismReturnsToItsStart) {
  constexpr int sides = 17;
  const double radius = 0.1, height = 0.3;
  Eigen::Matrix3Xd vertices(3, 2 * sides);
  for (int k = 0; k < sides; ++k) {
    const double angle = 2 * std::numbers::pi * k / sides;
    vertices.col(k) = Eigen::Vector3d(radius * std::cos(angle), 0, radius * std::sin(angle));
    vertices.col(sides + k) = Eigen::Vector3d(radius * std::cos(angle), height, radius * std::sin(angle));
  }
  Eigen::Matrix3Xi faces(3, 2 * sides);
  for (int k = 0; k < sides; ++k) {
    const int k1 = (k + 1) % sides;
    faces.col(2 * k) = Eigen::Vector3i(k, sides + k, k1);
    faces.col(2 * k + 1) = Eigen::Vector3i(k1, sides + k, sides + k1);
  }
  BodySurface surface(faces, static_cast<int>(vertices.cols()));
  surface.update(vertices);
  const double perimeter = sides * 2 * radius * std::sin(std::numbers::pi / sides);
  const SurfacePoint start{0, 0.3, 0.4};
  const Eigen::Vector3d along_ring = (vertices.col(1) - vertices.col(0)).normalized();
  for (double turns : {1.0, 3.0}) {
    const Eigen::Vector2d uv = uv_step(surface, vertices, 0, turns * perimeter * along_ring);
    const WalkResult walk = surface.walk(start, uv[0], uv[1]);
    EXPECT_NEAR(walk.walked_m, turns * perimeter, 1e-12);
    EXPECT_GE(walk.faces_crossed, static_cast<int>(turns * sides));
    EXPECT_LT((surface.position(walk.end) - surface.position(start)).norm(), 1e-9) << turns;
  }
}

TEST(BodySurface, LongWalksOnTheTemplateStayOnTheSurfaceAndConserveLength) {
  const auto model = make_template(Sex::kMale);
  BodySurface surface(model->faces, model->num_vertices());
  surface.update(model->v_template);
  std::mt19937 rng(9);
  for (int trial = 0; trial < 50; ++trial) {
    const int f = static_cast<int>(rng() % model->num_faces());
    const SurfacePoint start{f, 0.3, 0.3};
    const double angle = 0.1 * trial;
    const auto juv = surface.position_uv_jacobian(start);
    const Eigen::Vector3d t0 = juv.col(0).normalized(), n = juv.col(0).cross(juv.col(1)).normalized();
    const Eigen::Vector3d direction = std::cos(angle) * t0 + std::sin(angle) * n.cross(t0);
    const Eigen::Vector2d uv = juv.colPivHouseholderQr().solve(0.6 * direction);
    const WalkResult walk = surface.walk(start, uv[0], uv[1]);
    EXPECT_NEAR(walk.walked_m, 0.6, 1e-9);
    EXPECT_GT(walk.faces_crossed, 5);
    EXPECT_GE(walk.end.u, -1e-9);
    EXPECT_GE(walk.end.v, -1e-9);
    EXPECT_LE(walk.end.u + walk.end.v, 1 + 1e-9);
  }
}

}  // namespace
}  // namespace posefuse::body
