// The session's vertical: the floor or the IMU, whichever is known first, kept for the session;
// the floor's confidence from its spread; before either, the camera's y at half confidence.
#include "measures/session_vertical.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "measures/joint_angles.hpp"

namespace posefuse::measures {
namespace {

using geometry::Vec3;

constexpr double kDeg = std::numbers::pi / 180;

FloorVertical floor_with(const Vec3& up_K, double spread_deg) {
  FloorVertical floor;
  floor.up_K = up_K.normalized();
  floor.spread_rad = spread_deg * kDeg;
  floor.camera_height_m = 1.0;
  floor.points = 500;
  return floor;
}

TEST(SessionVertical, AssumedUntilMeasured) {
  const SessionVertical vertical;
  EXPECT_EQ(vertical.current().source, VerticalSource::kAssumed);
  EXPECT_EQ(vertical.current().up_K, Vec3::UnitY());
  EXPECT_DOUBLE_EQ(vertical.current().confidence, 0.5);
  EXPECT_FALSE(vertical.disagreement_rad().has_value());
}

TEST(SessionVertical, TheFirstMeasuredIsKeptAndTheOtherCompared) {
  const Vec3 floor_up(0, std::cos(10 * kDeg), -std::sin(10 * kDeg));
  const Vec3 imu_up(0, std::cos(12 * kDeg), -std::sin(12 * kDeg));
  SessionVertical floor_first;
  floor_first.add_floor(0, floor_with(floor_up, 0.3));
  floor_first.add_imu_up(imu_up);
  EXPECT_EQ(floor_first.current().source, VerticalSource::kFloor);
  EXPECT_LT((floor_first.current().up_K - floor_up).norm(), 1e-12);
  EXPECT_DOUBLE_EQ(floor_first.current().confidence, angle_confidence_from_rms_rad(0.3 * kDeg));
  ASSERT_TRUE(floor_first.disagreement_rad().has_value());
  EXPECT_NEAR(*floor_first.disagreement_rad() / kDeg, 2.0, 1e-9);

  SessionVertical imu_first;
  imu_first.add_imu_up(2 * imu_up);  // any length: it is a direction
  imu_first.add_floor(0, floor_with(floor_up, 0.3));
  EXPECT_EQ(imu_first.current().source, VerticalSource::kImu);
  EXPECT_LT((imu_first.current().up_K - imu_up).norm(), 1e-12);
  EXPECT_DOUBLE_EQ(imu_first.current().confidence, 1.0);
  EXPECT_FALSE(imu_first.wants_floor(0));                  // nothing left to look for
  EXPECT_FALSE(imu_first.disagreement_rad().has_value());  // the floor was not searched for
}

// A floor that bends or is small spreads more, and the thorax angles' confidence follows; one
// whose confidence falls below 0.5 is not kept, so that a later frame or the IMU can do better.
TEST(SessionVertical, AFloorsConfidenceFollowsItsSpread) {
  SessionVertical sure, less_sure, unsure;
  sure.add_floor(0, floor_with(Vec3::UnitY(), 0.5));
  less_sure.add_floor(0, floor_with(Vec3::UnitY(), 4.0));
  unsure.add_floor(0, floor_with(Vec3::UnitY(), 8.0));
  EXPECT_GT(sure.current().confidence, 0.99);
  EXPECT_EQ(less_sure.current().source, VerticalSource::kFloor);
  EXPECT_LT(less_sure.current().confidence, sure.current().confidence);
  EXPECT_GE(less_sure.current().confidence, 0.5);
  EXPECT_EQ(unsure.current().source, VerticalSource::kAssumed);
  EXPECT_TRUE(unsure.wants_floor(SessionVertical::kFloorRetryUs));
  const Vec3 imu_up(0, std::cos(3 * kDeg), std::sin(3 * kDeg));
  unsure.add_imu_up(imu_up);
  EXPECT_EQ(unsure.current().source, VerticalSource::kImu);
}

TEST(SessionVertical, TheFloorIsSoughtOncePerSecondUntilFound) {
  SessionVertical vertical;
  EXPECT_TRUE(vertical.wants_floor(0));
  vertical.add_floor(0, std::nullopt);
  EXPECT_FALSE(vertical.wants_floor(500'000));
  EXPECT_TRUE(vertical.wants_floor(SessionVertical::kFloorRetryUs));
  vertical.add_floor(SessionVertical::kFloorRetryUs, floor_with(Vec3::UnitY(), 0.2));
  EXPECT_FALSE(vertical.wants_floor(10 * SessionVertical::kFloorRetryUs));
  // Bad IMU directions are ignored.
  SessionVertical bad;
  bad.add_imu_up(Vec3::Zero());
  bad.add_imu_up(Vec3(std::numeric_limits<double>::quiet_NaN(), 1, 0));
  EXPECT_EQ(bad.current().source, VerticalSource::kAssumed);
}

}  // namespace
}  // namespace posefuse::measures
