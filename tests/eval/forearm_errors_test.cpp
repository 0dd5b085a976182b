#include "eval/forearm_errors.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "common/error.hpp"

using namespace posefuse::eval;

namespace {
Quat rot(double angle_deg, const Vec3& axis) {
  return Quat(Eigen::AngleAxisd(angle_deg * EIGEN_PI / 180.0, axis.normalized()));
}
}  // namespace

TEST(PaperOrientationError, Eqs14And15GiveTheRotationAngle) {
  const Quat gold = rot(70.0, Vec3(0.2, -0.7, 0.4));
  for (const double deg : {0.0, 11.34, 90.0, 179.79}) {
    const Quat measured = gold * rot(deg, Vec3(1.0, 2.0, -0.5));
    EXPECT_NEAR(paper_orientation_error_deg(measured, gold), deg, 1e-6) << deg;
    // Eq. 15 folds deg' > 180 (the quaternion on the other hemisphere) back.
    const Quat flipped(-measured.w(), -measured.x(), -measured.y(), -measured.z());
    EXPECT_NEAR(paper_orientation_error_deg(flipped, gold), deg, 1e-6) << deg;
  }
  // Not normalised, and a 180-degree flip about the forearm (the SDK's palm/dorsal confusion).
  const Quat scaled(2.0 * gold.w(), 2.0 * gold.x(), 2.0 * gold.y(), 2.0 * gold.z());
  EXPECT_NEAR(paper_orientation_error_deg(scaled, gold), 0.0, 1e-5);
  EXPECT_NEAR(paper_orientation_error_deg(gold * rot(180.0, Vec3::UnitY()), gold), 180.0, 1e-6);
}

TEST(SdkImuPosition, Eq16InterpolatesAtTheStrap) {
  const Vec3 elbow(0.1, 0.2, 2.0), wrist(0.1, 0.45, 1.95);
  const Vec3 d = sdk_imu_position(elbow, wrist, 0.18, 0.07);
  EXPECT_NEAR((d - elbow).norm(), 0.18 / 0.25 * (wrist - elbow).norm(), 1e-12);
  EXPECT_NEAR((d - elbow).cross(wrist - elbow).norm(), 0.0, 1e-12);
  EXPECT_THROW(sdk_imu_position(elbow, wrist, 0.0, 0.07), posefuse::Error);
  EXPECT_THROW(sdk_imu_position(elbow, wrist, 0.18, std::nan("")), posefuse::Error);
}

TEST(SummarizeErrors, RmsAndMaxOverSelectedFiniteFrames) {
  const std::vector<double> errors = {3.0, 4.0, std::nan(""), 12.0};
  const ErrorSummary all = summarize_errors(errors);
  EXPECT_EQ(all.count, 3u);
  EXPECT_NEAR(all.rms, std::sqrt((9.0 + 16.0 + 144.0) / 3.0), 1e-12);
  EXPECT_EQ(all.max, 12.0);
  const ErrorSummary gaps = summarize_errors(errors, {true, true, true, false});
  EXPECT_EQ(gaps.count, 2u);
  EXPECT_NEAR(gaps.rms, std::sqrt(12.5), 1e-12);
  EXPECT_EQ(gaps.max, 4.0);
  const ErrorSummary none = summarize_errors(errors, {false, false, false, false});
  EXPECT_EQ(none.count, 0u);
  EXPECT_TRUE(std::isnan(none.rms));
  EXPECT_THROW(summarize_errors(errors, {true}), posefuse::Error);
  EXPECT_NEAR(error_reduction_percent(84.25, 11.34), 86.54, 0.01);  // Table I's first row
}
