#include "imu/imu_sample.hpp"

#include <gtest/gtest.h>

#include <limits>

#include "common/error.hpp"

using posefuse::Error;
using posefuse::imu::ImuSample;
using posefuse::imu::validate_imu_stream;

namespace {
std::vector<ImuSample> still_stream(int n) {
  std::vector<ImuSample> out(n);
  for (int i = 0; i < n; ++i) {
    out[i].t_us = 12500 * i;
    out[i].acc_m_s2 = {0, 0, 9.81};
    out[i].mag_uT = {20, 0, -40};
  }
  return out;
}
}  // namespace

TEST(ValidateImuStream, AcceptsCleanStream) { EXPECT_NO_THROW(validate_imu_stream(still_stream(5))); }

TEST(ValidateImuStream, RejectsEmpty) { EXPECT_THROW(validate_imu_stream({}), Error); }

TEST(ValidateImuStream, NamesNaNGyroSample) {
  auto s = still_stream(5);
  s[3].gyr_rad_s.y() = std::numeric_limits<double>::quiet_NaN();
  try {
    validate_imu_stream(s, "arm");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "arm[3].gyr_rad_s");
    EXPECT_EQ(e.code(), posefuse::ErrorCode::kInvalidArgument);
  }
}

TEST(ValidateImuStream, RejectsNonMonotonicTimestamps) {
  auto s = still_stream(5);
  s[2].t_us = s[1].t_us;
  try {
    validate_imu_stream(s);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "imu[2].t_us");
  }
}

TEST(ValidateImuStream, AllowsMissingMagnetometer) {
  auto s = still_stream(3);
  s[1].mag_uT.setConstant(std::numeric_limits<double>::quiet_NaN());
  EXPECT_NO_THROW(validate_imu_stream(s));
}
