// Model mismatch: the rendered body is a finer, clothed version of the fitted template with the
// template's joints.
#include <gtest/gtest.h>

#include <cstdio>

#include "body/body_evaluator.hpp"
#include "body/template_generator.hpp"
#include "common/error.hpp"
#include "sim/render_model.hpp"

using namespace posefuse;
using namespace posefuse::sim;

TEST(RenderModel, SubdivisionQuadruplesFacesAndKeepsTheSurface) {
  const auto fitted = body::make_template(body::Sex::kMale);
  const body::SmplModel fine = subdivide(*fitted);
  EXPECT_EQ(fine.num_faces(), 4 * fitted->num_faces());
  // A closed genus-0 mesh: V - E + F = 2, and every edge gets one new vertex.
  const int edges = fitted->num_vertices() + fitted->num_faces() - 2;
  EXPECT_EQ(fine.num_vertices(), fitted->num_vertices() + edges);
  EXPECT_NO_THROW(body::validate(fine));
  // Midpoints lie on the old edges: the rest surface is unchanged.
  EXPECT_EQ(fine.v_template.leftCols(fitted->num_vertices()), fitted->v_template);
  // Posed, original vertices stay where the template puts them.
  const body::PoseLayout layout = body::PoseLayout::full_body();
  // Every DOF turned (a few tenths of a radian, alternating signs).
  Eigen::VectorXd theta = 0.4 * Eigen::VectorXd::LinSpaced(layout.size(), -1.0, 1.0);
  const Eigen::VectorXd betas = Eigen::VectorXd::LinSpaced(10, -1.0, 1.0);
  body::BodyEvaluator coarse_eval(fitted, layout), fine_eval(std::make_shared<body::SmplModel>(fine), layout);
  coarse_eval.evaluate(betas, theta, body::Derivatives::kNone);
  fine_eval.evaluate(betas, theta, body::Derivatives::kNone);
  EXPECT_LT((fine_eval.vertices().leftCols(fitted->num_vertices()) - coarse_eval.vertices()).cwiseAbs().maxCoeff(),
            1e-12);
  EXPECT_LT((fine_eval.joints() - coarse_eval.joints()).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(RenderModel, ClothingOffsetsAreBoundedSmoothAndKeepTheJoints) {
  const auto fitted = body::make_template(body::Sex::kFemale);
  const Eigen::VectorXd betas = Eigen::VectorXd::Zero(10);
  const ClothingOptions options;
  const RenderModel render = make_render_model(*fitted, betas, options, 3);
  const int v = fitted->num_vertices();
  ASSERT_EQ(render.surface_vertices, subdivide(*fitted).num_vertices());
  ASSERT_EQ(render.model->num_vertices(), render.surface_vertices + v);

  // Offsets of the template's own vertices (indices kept by subdivision).
  double largest = 0, torso_sum = 0, forearm_sum = 0;
  int torso = 0, forearm = 0;
  for (int i = 0; i < v; ++i) {
    const double offset = (render.model->v_template.col(i) - fitted->v_template.col(i)).norm();
    largest = std::max(largest, offset);
    if (render.material[static_cast<std::size_t>(i)] == Material::kShirt) {
      torso_sum += offset;
      ++torso;
    }
    if (render.forearm_arm[static_cast<std::size_t>(i)] >= 0) {
      forearm_sum += offset;
      ++forearm;
    }
  }
  std::printf("offsets: largest %.4f m, mean shirt %.4f m (%d), mean forearm %.4f m (%d)\n", largest, torso_sum / torso,
              torso, forearm_sum / forearm, forearm);
  EXPECT_LE(largest, options.torso_offset_m + 1e-12);
  ASSERT_GT(torso, 50);
  ASSERT_GT(forearm, 20);
  EXPECT_GT(torso_sum / torso, 0.005);      // clothing: several mm on average
  EXPECT_LT(forearm_sum / forearm, 0.004);  // forearms: soft tissue only
  EXPECT_GT(torso_sum / torso, 2 * forearm_sum / forearm);

  // Same joints as the fitted template in any pose (the regressor reads the ghosts).
  const body::PoseLayout layout = body::PoseLayout::full_body();
  const Eigen::VectorXd theta = 0.5 * Eigen::VectorXd::LinSpaced(layout.size(), 1.0, -1.0);
  body::BodyEvaluator a(fitted, layout), b(render.model, layout);
  a.evaluate(betas, theta, body::Derivatives::kNone);
  b.evaluate(betas, theta, body::Derivatives::kNone);
  EXPECT_LT((a.joints() - b.joints()).cwiseAbs().maxCoeff(), 1e-12);

  // The forearm coordinate runs from the elbow (0) to the wrist (forearm length).
  float low = 1e9f, high = -1e9f;
  for (std::size_t i = 0; i < render.forearm_coordinate_m.size(); ++i) {
    if (render.forearm_arm[i] != 1) continue;
    low = std::min(low, render.forearm_coordinate_m[i]);
    high = std::max(high, render.forearm_coordinate_m[i]);
  }
  EXPECT_LT(low, 0.03f);
  EXPECT_GT(high, 0.22f);

  // Deterministic for a seed, different for another.
  const RenderModel again = make_render_model(*fitted, betas, options, 3);
  const RenderModel other = make_render_model(*fitted, betas, options, 4);
  EXPECT_EQ(again.model->v_template, render.model->v_template);
  EXPECT_NE(other.model->v_template, render.model->v_template);
}

TEST(RenderModel, OptionsAreChecked) {
  const auto fitted = body::make_template(body::Sex::kMale);
  ClothingOptions bad;
  bad.subdivisions = 3;
  EXPECT_THROW(make_render_model(*fitted, Eigen::VectorXd::Zero(10), bad, 1), Error);
  bad = ClothingOptions();
  bad.torso_offset_m = -0.01;
  EXPECT_THROW(make_render_model(*fitted, Eigen::VectorXd::Zero(10), bad, 1), Error);
  EXPECT_THROW(make_render_model(*fitted, Eigen::VectorXd::Constant(11, 0.0), ClothingOptions(), 1), Error);
}
