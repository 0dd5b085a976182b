// IMU full scale (ImuSynthOptions::gyr_range_rad_s, acc_range_m_s2): each axis clips exactly at
// the range, values inside it are untouched.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "common/error.hpp"
#include "sim/imu_synth.hpp"
#include "test_motion.hpp"

using namespace posefuse;
using namespace posefuse::sim;
using std::numbers::pi;

namespace rigs = posefuse::sim::testing;

namespace {

// Spinning at 50 rad/s about (0.6, 0, 0.8) (30 and 40 rad/s on x and z, 1719 and 2292 deg/s)
// while the origin circles at 30 rad/s on 0.2 m (180 m/s^2, 18.4 g, centripetal).
SensorKinematics fast_motion() {
  const Vec3 axis(0.6, 0.0, 0.8);
  return SensorKinematics(
      rigs::sample_trajectory([](double t) { return Vec3(0.2 * std::cos(30 * t), 0.2 * std::sin(30 * t), 0); },
                              [&](double t) { return Quat(Eigen::AngleAxisd(50.0 * t, axis)); }, 0.0, 1.0));
}

}  // namespace

TEST(ImuSaturation, DefaultsAreTheCommonFullScales) {
  const ImuSynthOptions options;
  EXPECT_DOUBLE_EQ(options.gyr_range_rad_s, 2000.0 * pi / 180.0);
  EXPECT_DOUBLE_EQ(options.acc_range_m_s2, 16.0 * 9.80665);
}

TEST(ImuSaturation, AxesBeyondTheRangeClipExactly) {
  const SensorKinematics motion = fast_motion();
  const std::vector<double> t = uniform_times(0.1, 0.9, 80.0);
  ImuSynthOptions free;
  free.error_model = ImuErrorModel::none();
  free.gyr_range_rad_s = free.acc_range_m_s2 = std::numeric_limits<double>::infinity();
  ImuSynthOptions clipped = free;
  clipped.gyr_range_rad_s = 2000.0 * pi / 180.0;
  clipped.acc_range_m_s2 = 16.0 * kStandardGravity_m_s2;
  const ImuSynthResult a = synthesize_imu(motion, t, free), b = synthesize_imu(motion, t, clipped);
  int clipped_gyr = 0, clipped_acc = 0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    EXPECT_NEAR(a.samples[k].gyr_rad_s.z(), 40.0, 1e-6);  // beyond 34.9 rad/s without the range
    for (int i = 0; i < 3; ++i) {
      const double g = a.samples[k].gyr_rad_s[i], f = a.samples[k].acc_m_s2[i];
      EXPECT_EQ(b.samples[k].gyr_rad_s[i], std::clamp(g, -clipped.gyr_range_rad_s, clipped.gyr_range_rad_s));
      EXPECT_EQ(b.samples[k].acc_m_s2[i], std::clamp(f, -clipped.acc_range_m_s2, clipped.acc_range_m_s2));
      clipped_gyr += std::abs(g) > clipped.gyr_range_rad_s;
      clipped_acc += std::abs(f) > clipped.acc_range_m_s2;
    }
    EXPECT_EQ(b.samples[k].gyr_rad_s.z(), clipped.gyr_range_rad_s);
    EXPECT_NEAR(b.samples[k].gyr_rad_s.x(), 30.0, 1e-6);  // inside the range: untouched
  }
  EXPECT_EQ(clipped_gyr, static_cast<int>(t.size()));
  EXPECT_GT(clipped_acc, 0);
  EXPECT_LT(clipped_acc, 3 * static_cast<int>(t.size()));
}

TEST(ImuSaturation, NoisyReadingsNeverExceedTheRange) {
  ImuSynthOptions options;  // the default error model and ranges
  const ImuSynthResult imu = synthesize_imu(fast_motion(), uniform_times(0.1, 0.9, 80.0), options);
  int at_range = 0;
  for (const auto& s : imu.samples) {
    EXPECT_LE(s.gyr_rad_s.cwiseAbs().maxCoeff(), options.gyr_range_rad_s);
    EXPECT_LE(s.acc_m_s2.cwiseAbs().maxCoeff(), options.acc_range_m_s2);
    at_range += std::abs(s.gyr_rad_s.z()) == options.gyr_range_rad_s;
  }
  EXPECT_EQ(at_range, static_cast<int>(imu.samples.size()));
}

TEST(ImuSaturation, RejectsRangesThatAreNotPositive) {
  const SensorKinematics motion = fast_motion();
  ImuSynthOptions options;
  options.gyr_range_rad_s = 0;
  EXPECT_THROW(synthesize_imu(motion, {0.5}, options), Error);
  options = {};
  options.acc_range_m_s2 = std::nan("");
  EXPECT_THROW(synthesize_imu(motion, {0.5}, options), Error);
}
