#include "imu/vector_observation.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "synthetic_imu.hpp"

using namespace posefuse::imu;
using namespace posefuse::imu::testing;

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}

// A sensor whose axes coincide with W (x north, y west, z up) observes the identity.
TEST(VectorObservation, SensorAlignedWithWorldGivesIdentity) {
  const VectorObservation obs = observe_W_from_A(up_specific_force_W(), earth_field_W());
  ASSERT_TRUE(obs.ok());
  EXPECT_LT(quat_distance(obs.W_from_A, Quat::Identity()), 1e-15);
}

// Sensor x axis pointing east: W_from_A takes A's x to W's -y (east = -west), a -90 degree yaw.
TEST(VectorObservation, FrameDirectionsAreNorthWestUp) {
  const Quat W_from_A(Eigen::AngleAxisd(-EIGEN_PI / 2, Vec3::UnitZ()));
  const ImuSample s = ideal_sample(0, W_from_A, Vec3::Zero());
  const VectorObservation obs = observe_W_from_A(s.acc_m_s2, s.mag_uT);
  ASSERT_TRUE(obs.ok());
  EXPECT_LT((obs.W_from_A * Vec3::UnitX() - Vec3(0, -1, 0)).norm(), 1e-12);
  const Mat3 rows = W_from_A_matrix_from_vectors(s.acc_m_s2, s.mag_uT, {}, nullptr);
  // Rows are north, west, up seen from A.
  EXPECT_LT((rows.row(2).transpose() - s.acc_m_s2.normalized()).norm(), 1e-12);
  EXPECT_LT((rows.row(0).transpose() - W_from_A.conjugate() * Vec3::UnitX()).norm(), 1e-12);
  EXPECT_LT((rows.row(1).transpose() - W_from_A.conjugate() * Vec3::UnitY()).norm(), 1e-12);
}

// Eq. 1 + van Waveren recovers the true orientation and agrees with Eigen's conversion of the
// same matrix, for many random orientations; magnitudes of acc and mag do not matter.
TEST(VectorObservation, MatchesTruthAndEigenForRandomOrientations) {
  std::mt19937 rng(3);
  for (int i = 0; i < 5000; ++i) {
    const Quat truth = random_orientation(rng);
    ImuSample s = ideal_sample(0, truth, Vec3::Zero());
    s.acc_m_s2 *= 0.7;
    s.mag_uT *= 1.3;
    ObservationStatus status;
    const Mat3 matrix = W_from_A_matrix_from_vectors(s.acc_m_s2, s.mag_uT, {}, &status);
    ASSERT_EQ(status, ObservationStatus::kOk);
    EXPECT_LT((matrix * matrix.transpose() - Mat3::Identity()).norm(), 1e-12);
    EXPECT_NEAR(matrix.determinant(), 1.0, 1e-12);
    const VectorObservation obs = observe_W_from_A(s.acc_m_s2, s.mag_uT);
    ASSERT_TRUE(obs.ok());
    EXPECT_NEAR(std::abs(obs.W_from_A.dot(Quat(matrix))), 1.0, 1e-12);
    EXPECT_LT(quat_distance(obs.W_from_A, truth), 1e-13);
  }
}

TEST(VectorObservation, DegenerateInputGivesNoObservationAndNoNaN) {
  const Vec3 acc = up_specific_force_W();
  const Vec3 mag = earth_field_W();
  struct Case {
    Vec3 acc, mag;
    ObservationStatus expected;
  };
  const Case cases[] = {
      {Vec3::Zero(), mag, ObservationStatus::kNoGravity},
      {acc, Vec3::Zero(), ObservationStatus::kNoMagneticField},
      {acc, Vec3(kNaN, kNaN, kNaN), ObservationStatus::kNonFinite},
      {Vec3(0, kNaN, 9.8), mag, ObservationStatus::kNonFinite},
      {acc, Vec3(std::numeric_limits<double>::infinity(), 0, 0), ObservationStatus::kNonFinite},
      {acc, Vec3(0, 0, -40), ObservationStatus::kFieldAlongGravity},
      {acc, Vec3(0.5, 0, 40), ObservationStatus::kFieldAlongGravity},  // 0.7 deg off vertical
  };
  for (const Case& c : cases) {
    const VectorObservation obs = observe_W_from_A(c.acc, c.mag);
    EXPECT_EQ(obs.status, c.expected) << observation_status_name(obs.status);
    EXPECT_FALSE(obs.ok());
    EXPECT_TRUE(obs.W_from_A.coeffs().allFinite());
  }
}

// Eq. 2: over a slow 720 degree turn the raw van Waveren output flips sign (its pivot
// changes); choosing the member of {q, -q} next to the previous output never does.
TEST(VectorObservation, SignRuleKeepsSlow720DegreeTurnContinuous) {
  const Vec3 axis = Vec3(0.3, -0.5, 0.8).normalized();
  const Quat start(Eigen::AngleAxisd(0.4, Vec3(1, 1, 0).normalized()));
  const int steps = 7200;
  Quat previous = Quat::Identity();
  int raw_sign_flips = 0;
  Quat previous_raw = Quat::Identity();
  for (int i = 0; i <= steps; ++i) {
    const Quat truth = start * Quat(Eigen::AngleAxisd(4.0 * EIGEN_PI * i / steps, axis));
    const ImuSample s = ideal_sample(0, truth, Vec3::Zero());
    const VectorObservation raw = observe_W_from_A(s.acc_m_s2, s.mag_uT);
    const VectorObservation obs = observe_W_from_A_near(s.acc_m_s2, s.mag_uT, previous);
    ASSERT_TRUE(obs.ok());
    if (i > 0) {
      EXPECT_GT(obs.W_from_A.dot(previous), 0.99) << "sign jump at step " << i;
      if (raw.W_from_A.dot(previous_raw) < 0) ++raw_sign_flips;
    }
    previous = obs.W_from_A;
    previous_raw = raw.W_from_A;
  }
  EXPECT_GT(raw_sign_flips, 0) << "the test turn should exercise the sign ambiguity";
}
