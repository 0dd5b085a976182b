#include "imu/accel_calibration.hpp"

#include <gtest/gtest.h>

#include <random>

#include "common/error.hpp"
#include "expect_error.hpp"
#include "synthetic_imu.hpp"

using namespace posefuse::imu;
using namespace posefuse::imu::testing;

namespace {

constexpr double kG = 9.80665;

// A typical MEMS error: 0.15 m/s^2 offsets, 1-3% scale errors, ~1 degree cross-axis coupling.
Mat3 scale_error() {
  Mat3 m;
  m << 1.02, 0.012, -0.008, 0.012, 0.985, 0.015, -0.008, 0.015, 1.03;
  return m;
}
const Vec3 kOffset(0.15, -0.12, 0.2);

// Mean reading of a still sensor at each orientation, with `noise` left after averaging.
std::vector<Vec3> still_means(const std::vector<Quat>& orientations, double noise, std::mt19937& rng) {
  std::vector<Vec3> out;
  for (const Quat& W_from_A : orientations) {
    const Vec3 true_A = W_from_A.conjugate() * Vec3(0, 0, kG);
    out.push_back(scale_error() * true_A + kOffset + random_vector(rng, noise));
  }
  return out;
}

std::vector<Quat> random_orientations(int count, std::mt19937& rng) {
  std::vector<Quat> out;
  for (int i = 0; i < count; ++i) out.push_back(random_orientation(rng));
  return out;
}

void expect_refusal(const std::vector<Vec3>& means, const std::string& message_part) {
  posefuse::testing::expect_error([&] { calibrate_accelerometer(means); }, posefuse::ErrorCode::kFailedPrecondition,
                                  "acc_samples", message_part);
}

}  // namespace

// 36 orientations (the paper asks for > 30), 0.005 m/s^2 noise left after averaging ~1 s.
TEST(AccelCalibration, RecoversOffsetAndScaleFromManyOrientations) {
  std::mt19937 rng(8);
  const std::vector<Vec3> means = still_means(random_orientations(36, rng), 0.005, rng);
  const AccelCalibrationResult result = calibrate_accelerometer(means);
  EXPECT_LT((result.calibration.offset_m_s2 - kOffset).norm(), 0.01);
  // The correction scales to the known g, so it is the inverse of the (symmetric) error matrix.
  EXPECT_LT((result.calibration.correction - scale_error().inverse()).norm(), 0.01);
  EXPECT_GT(result.report.relative_spread_before, 0.01);
  EXPECT_LT(result.report.relative_spread_after, 0.001);
  EXPECT_EQ(result.report.orientation_count, 36u);
  for (const Vec3& m : means) EXPECT_NEAR(result.calibration.apply(m).norm(), kG, 0.01);
}

// Nine orientations determine the nine coefficients exactly: without noise the fit is exact.
// Each axis up and down, and three sensor diagonals up (nine random ones are often too poorly
// spread for the condition-number limit).
TEST(AccelCalibration, NineNoiseFreeOrientationsAreExact) {
  std::mt19937 rng(9);
  std::vector<Quat> orientations;
  for (const Vec3& up_A : {Vec3(1, 0, 0), Vec3(-1, 0, 0), Vec3(0, 1, 0), Vec3(0, -1, 0), Vec3(0, 0, 1), Vec3(0, 0, -1),
                           Vec3(1, 1, 1), Vec3(-1, 1, -1), Vec3(1, -1, -1)}) {
    // W_from_A taking the sensor direction up_A to W's up.
    orientations.push_back(Quat::FromTwoVectors(up_A.normalized(), Vec3::UnitZ()));
  }
  const std::vector<Vec3> means = still_means(orientations, 0.0, rng);
  const AccelCalibrationResult result = calibrate_accelerometer(means);
  EXPECT_LT((result.calibration.offset_m_s2 - kOffset).norm(), 1e-8);
  EXPECT_LT((result.calibration.correction - scale_error().inverse()).norm(), 1e-8);
}

TEST(AccelCalibration, RefusesTooFewOrientations) {
  std::mt19937 rng(10);
  expect_refusal(still_means(random_orientations(8, rng), 0.005, rng), "8 still orientations");
}

// Turning the sensor about one horizontal axis only: the readings lie in a plane.
TEST(AccelCalibration, RefusesPlanarOrientations) {
  std::mt19937 rng(11);
  std::vector<Quat> orientations;
  for (int i = 0; i < 36; ++i) orientations.emplace_back(Eigen::AngleAxisd(i * 0.17, Vec3::UnitX()));
  expect_refusal(still_means(orientations, 0.005, rng), "do not determine an ellipsoid");
}

// All orientations within 25 degrees of upright: the ellipsoid is seen only through a small cap.
TEST(AccelCalibration, RefusesClusteredOrientations) {
  std::mt19937 rng(12);
  std::vector<Quat> orientations;
  std::uniform_real_distribution<double> angle(0.0, 25.0 * kDeg);
  for (int i = 0; i < 36; ++i) {
    orientations.emplace_back(Eigen::AngleAxisd(angle(rng), random_vector(rng, 1.0).normalized()));
  }
  expect_refusal(still_means(orientations, 0.005, rng), "do not determine an ellipsoid");
}

TEST(AccelCalibration, DefaultIsFactoryIdentityAndBadInputIsRejected) {
  EXPECT_EQ(AccelCalibration{}.apply(Vec3(0.1, 0.2, 9.7)), Vec3(0.1, 0.2, 9.7));
  std::mt19937 rng(13);
  std::vector<Vec3> means = still_means(random_orientations(12, rng), 0.005, rng);
  means[3].x() = std::nan("");
  posefuse::testing::expect_error([&] { calibrate_accelerometer(means); }, posefuse::ErrorCode::kInvalidArgument,
                                  "acc_samples[3]");
  means[3].x() = 0.0;
  AccelCalibrationParams bad;
  bad.gravity_m_s2 = -1.0;
  posefuse::testing::expect_error([&] { calibrate_accelerometer(means, bad); }, posefuse::ErrorCode::kInvalidArgument,
                                  "accel.gravity_m_s2");
}
