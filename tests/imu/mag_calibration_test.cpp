#include "imu/mag_calibration.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "common/error.hpp"
#include "expect_error.hpp"
#include "synthetic_imu.hpp"

using namespace posefuse::imu;
using namespace posefuse::imu::testing;

namespace {

struct Distortion {
  Mat3 soft_iron;  // symmetric, det 1
  Vec3 hard_iron_uT;
};

Distortion test_distortion() {
  const Mat3 axes = Quat(Eigen::AngleAxisd(0.6, Vec3(1, -1, 2).normalized())).toRotationMatrix();
  const Vec3 scales(1.25, 0.9, 1.0 / (1.25 * 0.9));
  return {axes * scales.asDiagonal() * axes.transpose(), Vec3(12.0, -30.0, 7.5)};
}

// Readings of the earth field (48 uT) through the distortion, for random sensor orientations.
std::vector<Vec3> rotated_readings(int count, const Distortion& d, double noise_uT, std::mt19937& rng) {
  std::vector<Vec3> out;
  for (int i = 0; i < count; ++i) {
    const Vec3 field_A = random_orientation(rng).conjugate() * earth_field_W();
    out.push_back(d.soft_iron * field_A + d.hard_iron_uT + random_vector(rng, noise_uT));
  }
  return out;
}

void expect_refusal(const std::vector<Vec3>& readings, const std::string& message_part) {
  posefuse::testing::expect_error([&] { calibrate_magnetometer(readings); }, posefuse::ErrorCode::kFailedPrecondition,
                                  "mag_samples", message_part);
}

}  // namespace

// 3000 readings as in the paper, 0.3 uT noise. With det(soft iron) = 1 the volume-preserving
// scale makes the correction exactly the inverse soft iron, and |m| the true 48 uT.
TEST(MagCalibration, RecoversHardAndSoftIron) {
  std::mt19937 rng(42);
  const Distortion d = test_distortion();
  const std::vector<Vec3> raw = rotated_readings(3000, d, 0.3, rng);
  const MagCalibrationResult result = calibrate_magnetometer(raw);
  const MagCalibration& cal = result.calibration;
  EXPECT_LT((cal.center_uT - d.hard_iron_uT).norm(), 0.1);
  EXPECT_LT((cal.correction - d.soft_iron.inverse()).norm(), 0.01);
  EXPECT_NEAR(cal.field_strength_uT, 48.0, 0.1);
  // Radii are 48 uT times the soft-iron scales, along the soft-iron axes.
  const Mat3 shape = cal.axes * cal.radii_uT.asDiagonal() * cal.axes.transpose();
  EXPECT_LT((shape - 48.0 * d.soft_iron).norm(), 0.3);
  EXPECT_NEAR(cal.axes.determinant(), 1.0, 1e-12);

  const MagCalibrationReport& report = result.report;
  EXPECT_EQ(report.sample_count, 3000u);
  EXPECT_GT(report.relative_spread_before, 0.1);
  // Noise alone gives 0.3 / 48 = 0.006.
  EXPECT_LT(report.relative_spread_after, 0.008);
  EXPECT_GT(report.direction_coverage, 0.97);

  // A calibrated reading points where the true field does.
  const Quat W_from_A(Eigen::AngleAxisd(2.2, Vec3(0.3, 0.1, -1).normalized()));
  const Vec3 true_A = W_from_A.conjugate() * earth_field_W();
  const Vec3 corrected = cal.apply(d.soft_iron * true_A + d.hard_iron_uT);
  EXPECT_LT(posefuse::geometry::Quat::FromTwoVectors(corrected, true_A).vec().norm() * 2.0, 0.2 * kDeg);
}

TEST(MagCalibration, SkipsMissingReadingsAndRejectsInfinite) {
  std::mt19937 rng(1);
  std::vector<Vec3> raw = rotated_readings(1000, test_distortion(), 0.3, rng);
  raw[10].setConstant(std::numeric_limits<double>::quiet_NaN());
  const MagCalibrationResult result = calibrate_magnetometer(raw);
  EXPECT_EQ(result.report.sample_count, 999u);
  EXPECT_EQ(result.report.missing_count, 1u);
  EXPECT_TRUE(result.calibration.apply(raw[10]).array().isNaN().all());  // missing stays missing
  raw[20].y() = std::numeric_limits<double>::infinity();
  posefuse::testing::expect_error([&] { calibrate_magnetometer(raw); }, posefuse::ErrorCode::kInvalidArgument,
                                  "mag_samples[20]");
}

// A sensor turned about one axis only (here about W's vertical, the usual mistake of turning it
// on a table) traces a ring: poor coverage, refused before fitting.
TEST(MagCalibration, RefusesPlanarRotation) {
  std::mt19937 rng(2);
  const Distortion d = test_distortion();
  const Quat tilt(Eigen::AngleAxisd(0.3, Vec3::UnitX()));
  std::vector<Vec3> raw;
  for (int i = 0; i < 3000; ++i) {
    const Quat W_from_A = Quat(Eigen::AngleAxisd(i * 0.01, Vec3::UnitZ())) * tilt;
    raw.push_back(d.soft_iron * (W_from_A.conjugate() * earth_field_W()) + d.hard_iron_uT + random_vector(rng, 0.3));
  }
  expect_refusal(raw, "of the directions");
}

TEST(MagCalibration, RefusesTooFewSamples) {
  std::mt19937 rng(3);
  expect_refusal(rotated_readings(150, test_distortion(), 0.3, rng), "150 usable readings");
  expect_refusal({}, "0 usable readings");
}

TEST(MagCalibration, DefaultIsIdentity) {
  const MagCalibration identity;
  EXPECT_EQ(identity.apply(Vec3(1, -2, 3)), Vec3(1, -2, 3));
}

TEST(DirectionCoverage, CountsEqualAreaBins) {
  std::mt19937 rng(4);
  std::vector<Vec3> uniform;
  for (int i = 0; i < 5000; ++i) uniform.push_back(random_vector(rng, 1.0));
  EXPECT_EQ(direction_coverage(uniform, Vec3::Zero()), 1.0);
  const std::vector<Vec3> one_direction(100, Vec3(1, 2, 3));
  EXPECT_EQ(direction_coverage(one_direction, Vec3::Zero()), 1.0 / kDirectionBins);
  // The upper hemisphere is exactly half of the bins.
  std::vector<Vec3> upper;
  for (const Vec3& v : uniform) upper.push_back(Vec3(v.x(), v.y(), std::abs(v.z())));
  EXPECT_EQ(direction_coverage(upper, Vec3::Zero()), 0.5);
  EXPECT_EQ(direction_coverage({Vec3::Zero()}, Vec3::Zero()), 0.0);
}

namespace {
// Points on the one-sheet hyperboloid x^2 + y^2 - z^2 = 1 (|z| <= 1.2), scaled and shifted: they
// cover 75% of the directions from their mean and determine the quadric well, but it is not
// positive definite.
std::vector<Vec3> hyperboloid_points(double scale) {
  std::vector<Vec3> points;
  for (int i = 0; i < 60; ++i) {
    for (int j = 0; j < 10; ++j) {
      const double z = -1.2 + 0.24 * j;
      const double r = std::sqrt(1.0 + z * z);
      const double a = i * 2.0 * EIGEN_PI / 60.0;
      points.push_back(scale * Vec3(r * std::cos(a), r * std::sin(a), z) + Vec3(3, 1, -2));
    }
  }
  return points;
}
}  // namespace

TEST(EllipsoidFit, RefusesHyperboloid) {
  posefuse::testing::expect_error([&] { fit_ellipsoid(hyperboloid_points(1.0), "points", 1e3); },
                                  posefuse::ErrorCode::kFailedPrecondition, "points", "not an ellipsoid");
}

// Readings that are no ellipsoid (a disturbed field) are refused by the calibration itself.
TEST(MagCalibration, RefusesReadingsThatAreNotAnEllipsoid) {
  expect_refusal(hyperboloid_points(40.0), "not an ellipsoid");
}

TEST(EllipsoidFit, ExactOnNoiseFreeEllipsoid) {
  std::mt19937 rng(5);
  const Mat3 axes = Quat(Eigen::AngleAxisd(1.0, Vec3(0, 1, 1).normalized())).toRotationMatrix();
  const Vec3 radii(3.0, 2.0, 0.5);
  const Vec3 center(-4, 5, 6);
  std::vector<Vec3> points;
  for (int i = 0; i < 50; ++i) {
    points.push_back(center + axes * radii.asDiagonal() * random_vector(rng, 1.0).normalized());
  }
  const EllipsoidFit fit = fit_ellipsoid(points, "points", 1e3);
  EXPECT_LT((fit.center - center).norm(), 1e-9);
  const Mat3 shape = fit.axes * fit.radii.asDiagonal() * fit.axes.transpose();
  EXPECT_LT((shape - axes * radii.asDiagonal() * axes.transpose()).norm(), 1e-9);
  for (const Vec3& p : points) {
    EXPECT_NEAR((fit.sphere_from_ellipsoid(1.0) * (p - fit.center)).norm(), 1.0, 1e-9);
  }
}
