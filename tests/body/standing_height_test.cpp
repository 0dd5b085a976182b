#include "body/standing_height.hpp"

#include <gtest/gtest.h>

#include "body/template_generator.hpp"
#include "common/error.hpp"

namespace posefuse::body {
namespace {

TEST(StandingHeight, IsTheRestMeshFromCrownToSole) {
  const auto model = shared_template(Sex::kFemale);
  const StandingHeight h = standing_height(*model, Eigen::VectorXd::Zero(10));
  const double crown = model->v_template.row(1).maxCoeff(), sole = model->v_template.row(1).minCoeff();
  EXPECT_DOUBLE_EQ(h.height_m, crown - sole);
  EXPECT_GT(h.height_m, 1.4);
  EXPECT_LT(h.height_m, 1.9);
}

// Beta 0 scales the template uniformly about the floor: the height grows in proportion.
TEST(StandingHeight, GradientIsTheHeightsChangePerBeta) {
  const auto model = shared_template(Sex::kMale);
  Eigen::VectorXd beta = Eigen::VectorXd::Zero(10);
  beta << 0.8, -0.5, 0.6, 1.0, -0.7, 0.6, 0.4, 0.5, -0.3, 0.5;
  const StandingHeight h = standing_height(*model, beta);
  ASSERT_EQ(h.gradient.size(), 10);
  for (int b = 0; b < 10; ++b) {
    Eigen::VectorXd moved = beta;
    moved[b] += 1e-4;
    EXPECT_NEAR((standing_height(*model, moved).height_m - h.height_m) / 1e-4, h.gradient[b], 1e-6) << "beta " << b;
  }
  EXPECT_GT(h.gradient[0], 0.02);  // stature
  // Fewer betas are zero padded; more are refused.
  EXPECT_DOUBLE_EQ(
      standing_height(*model, beta.head(3)).height_m,
      standing_height(*model, (Eigen::VectorXd(10) << beta.head(3), Eigen::VectorXd::Zero(7)).finished()).height_m);
  try {
    standing_height(*model, Eigen::VectorXd::Zero(11));
    ADD_FAILURE() << "11 betas accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "beta");
  }
}

}  // namespace
}  // namespace posefuse::body
