// The whole chain: arm IMU -> base IMU (broadcasts) -> camera (buzzer events).
#include <gtest/gtest.h>

#include <cmath>

#include "../imu/expect_error.hpp"
#include "sync/clock_map.hpp"

namespace posefuse::sync {
namespace {

using posefuse::testing::expect_error;

TEST(ClockMap, ChainsArmThroughBaseToCamera) {
  // True clocks against the camera: base = camera * (1 + 20 ppm) + 3 s,
  // arm = camera * (1 - 10 ppm) - 2 s.
  auto base_of = [](double cam) { return cam * (1.0 + 20e-6) + 3e6; };
  auto arm_of = [](double cam) { return cam * (1.0 - 10e-6) - 2e6; };
  const ClockFit camera_from_base = fit_linear_clock({{base_of(1e6), 1e6, 50.0}, {base_of(500e6), 500e6, 50.0}});
  std::vector<ClockObservation> arm_to_base;
  for (double cam = 0; cam < 500e6; cam += 1e6) arm_to_base.push_back({arm_of(cam), base_of(cam), 128.0});
  const ClockFit base_from_arm = fit_linear_clock(arm_to_base);

  ClockMap map;
  map.add_direct("base", camera_from_base.clock);
  map.add_via("arm", "base", base_from_arm.clock);
  for (double cam : {0.0, 250e6, 499e6}) {
    EXPECT_NEAR(map.to_camera_us("arm", arm_of(cam)), cam, 1.0);
    EXPECT_NEAR(map.to_camera_us("base", base_of(cam)), cam, 1.0);
    EXPECT_NEAR(map.to_camera_us(ClockMap::kCamera, cam), cam, 0.0);
    EXPECT_GE(map.sigma_us("arm", arm_of(cam)), map.sigma_us("base", base_of(cam)) - 1e-9);
  }
}

TEST(ClockMap, RefusesUnknownAndDuplicateDevices) {
  ClockMap map;
  map.add_direct("base", LinearClock{});
  expect_error([&] { map.add_direct("base", LinearClock{}); }, ErrorCode::kInvalidArgument, "device");
  expect_error([&] { map.add_via("arm", "nobody", LinearClock{}); }, ErrorCode::kNotFound, "via");
  expect_error([&] { map.to_camera_us("arm", 0.0); }, ErrorCode::kNotFound, "device");
  expect_error([&] { map.to_camera_us("base", NAN); }, ErrorCode::kInvalidArgument, "device_us");
}

}  // namespace
}  // namespace posefuse::sync
