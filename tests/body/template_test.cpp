#include <gtest/gtest.h>

#include "body/body_evaluator.hpp"
#include "body/mesh_topology.hpp"
#include "body/template_generator.hpp"

namespace posefuse::body {
namespace {

class TemplateTest : public ::testing::TestWithParam<Sex> {};

TEST_P(TemplateTest, IsClosedOrientedManifoldSphere) {
  const auto model = make_template(GetParam());
  const MeshTopologyReport report = check_topology(model->faces, model->num_vertices());
  EXPECT_EQ(report.num_boundary_edges, 0);
  EXPECT_EQ(report.num_nonmanifold_edges, 0);
  EXPECT_EQ(report.num_misoriented_edges, 0);
  EXPECT_EQ(report.num_nonmanifold_vertices, 0);
  EXPECT_EQ(report.num_degenerate_faces, 0);
  EXPECT_EQ(report.num_unreferenced, 0);
  EXPECT_EQ(report.euler_characteristic, 2);                        // genus 0
  EXPECT_GT(signed_volume(model->v_template, model->faces), 0.03);  // outward normals, ~60-80 l
  EXPECT_GT(model->num_vertices(), 800);
  EXPECT_LT(model->num_vertices(), 1200);
  std::cout << "vertices " << model->num_vertices() << " faces " << model->num_faces() << " volume "
            << signed_volume(model->v_template, model->faces) << "\n";
}

TEST_P(TemplateTest, IsDeterministic) {
  const auto a = make_template(GetParam()), b = make_template(GetParam());
  EXPECT_EQ(a->v_template, b->v_template);
  EXPECT_EQ(a->shapedirs, b->shapedirs);
  EXPECT_EQ(a->faces, b->faces);
  EXPECT_EQ(Eigen::MatrixXd(a->weights), Eigen::MatrixXd(b->weights));
  EXPECT_EQ(Eigen::MatrixXd(a->J_regressor), Eigen::MatrixXd(b->J_regressor));
}

TEST_P(TemplateTest, SharedTemplateIsBuiltOnceAndEqualsAFreshOne) {
  const auto shared = shared_template(GetParam());
  EXPECT_EQ(shared.get(), shared_template(GetParam()).get());
  const Sex other = GetParam() == Sex::kMale ? Sex::kFemale : Sex::kMale;
  EXPECT_NE(shared.get(), shared_template(other).get());
  const auto fresh = make_template(GetParam());
  EXPECT_EQ(shared->v_template, fresh->v_template);
  EXPECT_EQ(shared->shapedirs, fresh->shapedirs);
  EXPECT_EQ(Eigen::MatrixXd(shared->weights), Eigen::MatrixXd(fresh->weights));
}

INSTANTIATE_TEST_SUITE_P(Sexes, TemplateTest, ::testing::Values(Sex::kMale, Sex::kFemale));

}  // namespace
}  // namespace posefuse::body

namespace posefuse::body {
namespace {

struct Measure {
  const char* name;
  int a, b;
};
constexpr Measure kMeasures[] = {
    {"pelvis-spine1", kPelvis, kSpine1},
    {"spine1-spine2", kSpine1, kSpine2},
    {"spine2-spine3", kSpine2, kSpine3},
    {"spine3-neck", kSpine3, kNeck},
    {"neck-head", kNeck, kHead},
    {"l_hip-knee", kLeftHip, kLeftKnee},
    {"r_knee-ankle", kRightKnee, kRightAnkle},
    {"l_shoulder-elbow", kLeftShoulder, kLeftElbow},
    {"r_elbow-wrist", kRightElbow, kRightWrist},
    {"l_collar-shoulder", kLeftCollar, kLeftShoulder},
    {"shoulder-shoulder", kLeftShoulder, kRightShoulder},
    {"hip-hip", kLeftHip, kRightHip},
};

// Documented change (metres per unit beta) of each measure; see template_shape_directions().
double expected_change(int direction, const Measure& m, double rest_length) {
  const std::string name = m.name;
  switch (direction) {
    case 0: return 0.04 * rest_length;
    case 1:
      if (name == "pelvis-spine1") return 0.006;
      if (name == "spine1-spine2") return 0.008;
      if (name == "spine2-spine3") return 0.004;
      if (name == "spine3-neck") return 0.007;
      return 0;
    case 2: return name == "l_hip-knee" || name == "r_knee-ankle" ? 0.015 : 0;
    case 3: return name == "l_shoulder-elbow" ? 0.015 : 0;
    case 4: return name == "r_elbow-wrist" ? 0.012 : 0;
    case 5: return name == "l_collar-shoulder" ? 0.012 : name == "shoulder-shoulder" ? 0.024 : 0;
    case 6: return name == "hip-hip" ? 0.016 : 0;
    case 9: return name == "neck-head" ? 0.06 * rest_length : 0;
    default: return 0;
  }
}

double length(const BodyEvaluator& e, const Measure& m) { return (e.joints().col(m.a) - e.joints().col(m.b)).norm(); }

TEST_P(TemplateTest, ShapeDirectionsChangeSegmentLengthsLinearlyAsDocumented) {
  const auto model = make_template(GetParam());
  ASSERT_EQ(model->num_betas(), kTemplateNumBetas);
  const PoseLayout layout = PoseLayout::upper_body();
  BodyEvaluator eval(model, layout);
  eval.evaluate(Eigen::VectorXd::Zero(10), layout.zero(), Derivatives::kNone);
  std::vector<double> rest;
  for (const Measure& m : kMeasures) rest.push_back(length(eval, m));
  for (int s = 0; s < kTemplateNumBetas; ++s)
    for (double amount : {-2.0, 1.0, 2.5}) {
      Eigen::VectorXd beta = Eigen::VectorXd::Zero(10);
      beta[s] = amount;
      eval.evaluate(beta, layout.zero(), Derivatives::kNone);
      for (size_t k = 0; k < std::size(kMeasures); ++k) {
        const double change = length(eval, kMeasures[k]) - rest[k];
        EXPECT_NEAR(change, amount * expected_change(s, kMeasures[k], rest[k]), 1e-9)
            << template_shape_directions()[s].name << " " << kMeasures[k].name << " beta " << amount;
      }
    }
}

TEST_P(TemplateTest, RegressedJointsAreInsideTheBodyAtPlausiblePlaces) {
  const auto model = make_template(GetParam());
  BodyEvaluator eval(model, PoseLayout::upper_body());
  eval.evaluate(Eigen::VectorXd::Zero(10), PoseLayout::upper_body().zero(), Derivatives::kNone);
  const auto& j = eval.joints();
  EXPECT_GT(j(1, kHead), j(1, kNeck));
  EXPECT_GT(j(1, kNeck), j(1, kSpine3));
  EXPECT_GT(j(1, kPelvis), j(1, kLeftKnee));
  EXPECT_GT(j(0, kLeftWrist), j(0, kLeftElbow));  // left is +x
  EXPECT_LT(j(0, kRightWrist), j(0, kRightElbow));
  const double stature = model->v_template.row(1).maxCoeff() - model->v_template.row(1).minCoeff();
  EXPECT_GT(stature, GetParam() == Sex::kMale ? 1.70 : 1.55);
  EXPECT_LT(stature, GetParam() == Sex::kMale ? 1.85 : 1.70);
  const double span = model->v_template.row(0).maxCoeff() - model->v_template.row(0).minCoeff();
  EXPECT_NEAR(span / stature, 1.0, 0.08);  // arm span ~ stature
}

// Posing within the usual range neither tears nor collapses faces. Linear blend skinning
// compresses the inside of a bent joint and stretches the outside; a tear or a collapse would
// show as edges far beyond these bounds (the groin crease at 90 deg hip flexion reaches ~0.33).
TEST_P(TemplateTest, SkinningKeepsFacesIntactInUsualRangeOfMotion) {
  const auto model = make_template(GetParam());
  const PoseLayout layout = PoseLayout::full_body();
  BodyEvaluator eval(model, layout);
  eval.evaluate(Eigen::VectorXd::Zero(10), layout.zero(), Derivatives::kNone);
  const Eigen::Matrix3Xd rest = eval.vertices();
  constexpr double kDeg = 3.14159265358979 / 180;
  const std::vector<std::vector<std::pair<const char*, double>>> poses = {
      {{"left_elbow_y", -120 * kDeg}, {"right_elbow_y", 120 * kDeg}},
      {{"left_shoulder_z", -80 * kDeg}, {"right_shoulder_z", 80 * kDeg}},
      {{"left_shoulder_y", -90 * kDeg}, {"right_shoulder_z", -60 * kDeg}, {"right_elbow_z", 20 * kDeg}},
      {{"left_hip_x", -90 * kDeg}, {"left_knee_x", 90 * kDeg}, {"right_hip_z", -30 * kDeg}},
      {{"spine1_x", 20 * kDeg},
       {"spine2_x", 20 * kDeg},
       {"spine3_y", 20 * kDeg},
       {"neck_x", 30 * kDeg},
       {"head_y", 50 * kDeg}},
      {{"left_collar_z", 25 * kDeg}, {"left_wrist_y", 60 * kDeg}, {"right_wrist_z", -40 * kDeg}},
  };
  for (const auto& pose : poses) {
    Eigen::VectorXd theta = layout.zero();
    for (const auto& [name, value] : pose) theta[layout.index_of(name)] = value;
    eval.evaluate(Eigen::VectorXd::Zero(10), theta, Derivatives::kNone);
    const auto& v = eval.vertices();
    double min_ratio = 1e9, max_ratio = 0;
    for (int f = 0; f < model->num_faces(); ++f)
      for (int k = 0; k < 3; ++k) {
        const int a = model->faces(k, f), b = model->faces((k + 1) % 3, f);
        const double ratio = (v.col(a) - v.col(b)).norm() / (rest.col(a) - rest.col(b)).norm();
        min_ratio = std::min(min_ratio, ratio);
        max_ratio = std::max(max_ratio, ratio);
      }
    EXPECT_GT(min_ratio, 0.3) << pose.front().first;
    EXPECT_LT(max_ratio, 2.5) << pose.front().first;
  }
}

}  // namespace
}  // namespace posefuse::body
