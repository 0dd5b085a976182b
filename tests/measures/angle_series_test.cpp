// A session's angle series and the repetitions of the one chosen (measures/angle_series.hpp).
#include "measures/angle_series.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace posefuse::measures {
namespace {

AngleValue value(double deg, double confidence) {
  return AngleValue{deg, true, false, confidence, AngleSource::kBodyModel};
}

// A trunk tilting +-18 deg three times at full confidence while the fitted left elbow scatters
// over 150 deg at confidence 0.05 (near full extension): the series chooses the tilt and counts
// its three repetitions. With the elbow as confident, its spread wins.
TEST(AngleSeries, ChoosesAConfidentAngleThatMovesOverAnUnsureOneThatScatters) {
  for (const double elbow_confidence : {0.05, 1.0}) {
    SCOPED_TRACE("elbow confidence " + std::to_string(elbow_confidence));
    AngleSeries series;
    std::mt19937 rng(13);
    std::uniform_real_distribution<double> scatter(0.0, 150.0);
    const double dt = 1.0 / 30;
    const int frames = 3 * 180 + 30;  // three 6 s tilts, 1 s of rest at the end
    for (int k = 0; k < frames; ++k) {
      const double t = k * dt;
      const double phase = std::fmod(t, 6.0) / 6.0;
      const double tilt = k < 3 * 180 ? 18 * std::sin(2 * std::numbers::pi * phase) : 0.0;
      JointAngles angles{};
      angles[static_cast<int>(Angle::kThoraxLateralTilt)] = value(tilt, 1.0);
      angles[static_cast<int>(Angle::kLeftElbowFlexion)] = value(scatter(rng), elbow_confidence);
      ASSERT_TRUE(series.add(t, angles));
    }
    const std::optional<SessionRepetitions> reps = series.repetitions(RepetitionOptions{});
    ASSERT_TRUE(reps.has_value());
    EXPECT_TRUE(reps->detected);
    if (elbow_confidence < kConfidentAt) {
      EXPECT_EQ(reps->angle, Angle::kThoraxLateralTilt);
      EXPECT_EQ(reps->summary.count, 3);
      EXPECT_EQ(reps->summary.confident_fraction, 1.0);
    } else {
      EXPECT_EQ(reps->angle, Angle::kLeftElbowFlexion);
    }
  }
}

// A shrug: the left elevation lifts 15 deg and back three times at full confidence while the
// unsure elbow, hanging, scatters over 10 deg. 15 deg is under the default minimum amplitude, but
// nothing moves more: the elevation is chosen and its three lifts count (counted_amplitude_deg).
TEST(AngleSeries, ASmallConfidentMotionIsChosenAndCountedWhenNothingMovesMore) {
  AngleSeries series;
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> scatter(0.0, 10.0);
  const double dt = 1.0 / 30;
  const int frames = 3 * 90 + 30;  // three 3 s lifts, 1 s of rest at the end
  for (int k = 0; k < frames; ++k) {
    const double t = k * dt;
    const double phase = std::fmod(t, 3.0) / 3.0;
    const double lift = k < 3 * 90 ? 7.5 * (1 - std::cos(2 * std::numbers::pi * phase)) : 0.0;
    JointAngles angles{};
    angles[static_cast<int>(Angle::kLeftElevation)] = value(8 + lift, 1.0);
    angles[static_cast<int>(Angle::kLeftElbowFlexion)] = value(scatter(rng), 0.05);
    ASSERT_TRUE(series.add(t, angles));
  }
  const std::optional<SessionRepetitions> reps = series.repetitions(RepetitionOptions{});
  ASSERT_TRUE(reps.has_value());
  EXPECT_EQ(reps->angle, Angle::kLeftElevation);
  EXPECT_EQ(reps->summary.count, 3);
  EXPECT_NEAR(reps->summary.mean_range_deg, 15.0, 0.1);
}

}  // namespace
}  // namespace posefuse::measures
