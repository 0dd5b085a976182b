#include "imu/gyro_bias_tracker.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "common/error.hpp"
#include "synthetic_imu.hpp"

using namespace posefuse::imu;
using namespace posefuse::imu::testing;

// Still sensor, bias (1.1, -0.6, 0.3) deg/s, white noise 0.3 deg/s: after 25 s at 80 Hz the
// estimate's standard error is sigma / sqrt(2 * 800 - 1) ~ 1.3e-4 rad/s (exponential window of
// 800); we allow 5e-4 rad/s (~4 standard errors, 0.03 deg/s).
TEST(GyroBiasTracker, ConvergesOnStillSensorWithKnownBias) {
  std::mt19937 rng(11);
  const Vec3 bias = Vec3(1.1, -0.6, 0.3) * kDeg;
  GyroBiasTracker tracker;
  for (int i = 0; i < 2000; ++i) tracker.update(bias + random_vector(rng, 0.3 * kDeg));
  EXPECT_GT(tracker.still_sample_count(), 1990);  // noise never reaches the 3 deg/s test
  EXPECT_LT((tracker.bias_rad_s() - bias).cwiseAbs().maxCoeff(), 5e-4);
}

TEST(GyroBiasTracker, IgnoresMovingSamples) {
  const Vec3 initial(0.01, 0.02, -0.01);
  GyroBiasTracker::Params params;
  params.initial_bias_rad_s = initial;
  GyroBiasTracker tracker(params);
  for (int i = 0; i < 500; ++i) {
    // Consecutive samples differ by 0.5 rad/s on one axis only: still not "all three within".
    tracker.update(Vec3((i % 2) ? 0.5 : 0.0, 0.001, 0.001));
  }
  EXPECT_EQ(tracker.still_sample_count(), 0);
  EXPECT_EQ(tracker.bias_rad_s(), initial);
}

// The window: exact mean while fewer than window_samples have been seen, then forgetting with
// factor 1 - 1/window: a bias step is followed by 1 - (1 - 1/N)^N ~ 63% after N samples.
TEST(GyroBiasTracker, AveragingWindowIsDocumentedExponentialMemory) {
  GyroBiasTracker::Params params;
  params.window_samples = 100;
  GyroBiasTracker tracker(params);
  const Vec3 before(0.01, 0.0, 0.0);
  const Vec3 after(0.02, 0.0, 0.0);
  for (int i = 0; i < 300; ++i) tracker.update(before);
  EXPECT_NEAR(tracker.bias_rad_s().x(), 0.01, 1e-15);
  tracker.update(after);  // a 0.01 rad/s step is below the 3 deg/s test: counts as still
  for (int i = 1; i < 100; ++i) tracker.update(after);
  const double fraction = 1.0 - std::pow(1.0 - 1.0 / 100.0, 100);
  EXPECT_NEAR(tracker.bias_rad_s().x(), 0.01 + 0.01 * fraction, 1e-12);
}

// The paper's test compares consecutive samples only, so a constant-rate turn looks still and is
// absorbed into the bias; the optional rate gate (off by default) prevents that.
TEST(GyroBiasTracker, ConstantRateTurnIsAbsorbedUnlessRateGateIsSet) {
  const Vec3 turn(0.0, 0.0, 0.5);  // ~29 deg/s
  GyroBiasTracker paper;
  GyroBiasTracker::Params gated_params;
  gated_params.max_still_rate_rad_s = 3.0 * kDeg;
  GyroBiasTracker gated(gated_params);
  for (int i = 0; i < 200; ++i) {
    paper.update(turn);
    gated.update(turn);
  }
  EXPECT_NEAR(paper.bias_rad_s().z(), 0.5, 1e-12);
  EXPECT_EQ(gated.bias_rad_s(), Vec3::Zero());
  EXPECT_EQ(gated.still_sample_count(), 0);
}

TEST(GyroBiasTracker, RejectsBadParams) {
  GyroBiasTracker::Params p;
  p.window_samples = 0;
  EXPECT_THROW(GyroBiasTracker{p}, posefuse::Error);
  p = {};
  p.still_threshold_rad_s = std::nan("");
  EXPECT_THROW(GyroBiasTracker{p}, posefuse::Error);
  p = {};
  p.initial_bias_rad_s.x() = std::nan("");
  EXPECT_THROW(GyroBiasTracker{p}, posefuse::Error);
}
