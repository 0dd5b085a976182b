#include "fit/height_shape.hpp"

#include <gtest/gtest.h>

#include "body/standing_height.hpp"
#include "body/template_generator.hpp"
#include "synthetic_frames.hpp"

namespace posefuse::fit {
namespace {

const body::SmplModel& female() { return *body::shared_template(body::Sex::kFemale); }

Eigen::VectorXd subject() {
  Eigen::VectorXd beta = Eigen::VectorXd::Zero(10);
  beta << 1.5, -1, 0.5, 0, 0, 0, 0, 0, 0, 0;
  return beta;
}

TEST(HeightShape, TheTemplatesOwnHeightGivesTheTemplate) {
  const double height = body::standing_height(female(), Eigen::VectorXd::Zero(10)).height_m;
  EXPECT_LT(shape_from_height(female(), height).norm(), 1e-9);
}

// The shape reaches the measured height (within its 1 cm sigma), with the smallest betas that do:
// no larger than the subject's own, and along the directions that move the height.
TEST(HeightShape, ReachesTheHeightWithTheSmallestShape) {
  const double height = body::standing_height(female(), subject()).height_m;
  const Eigen::VectorXd beta = shape_from_height(female(), height);
  EXPECT_NEAR(body::standing_height(female(), beta).height_m, height, 0.01);
  EXPECT_LE(beta.norm(), subject().norm());
  EXPECT_GT(beta[0], 0.5);  // taller than the template: mostly stature
  const Eigen::RowVectorXd gradient = body::standing_height(female(), beta).gradient;
  for (int b = 0; b < 10; ++b) {
    if (gradient[b] == 0) {
      EXPECT_EQ(beta[b], 0) << "beta " << b << " does not move the height";
    }
  }
  // A shorter subject: the other way.
  EXPECT_LT(shape_from_height(female(), body::standing_height(female(), -subject()).height_m)[0], -0.5);
}

TEST(HeightShape, RefusesAHeightNoAdultHas) {
  EXPECT_EQ(testing::error_field([] { shape_from_height(female(), 0.3); }), "height_m");
  EXPECT_EQ(testing::error_field([] { shape_from_height(female(), std::nan("")); }), "height_m");
  HeightShapeOptions bad;
  bad.height_sigma_m = 0;
  EXPECT_EQ(testing::error_field([&] { shape_from_height(female(), 1.6, bad); }),
            "height_shape_options.height_sigma_m");
}

}  // namespace
}  // namespace posefuse::fit
