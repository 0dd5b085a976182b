// Gap finding, boundary fits, eq. 12 and eq. 13 on exact synthetic data, and input validation.
#include <gtest/gtest.h>

#include "../imu/expect_error.hpp"
#include "forearm/gap_input.hpp"
#include "synthetic_arm.hpp"

namespace posefuse::forearm {
namespace {

using namespace posefuse::forearm::testing;
using posefuse::testing::expect_error;

TEST(GapInput, FindsGapsWithTheirBoundaries) {
  std::vector<TrackSample> track;
  for (int k = 0; k < 10; ++k) track.push_back({k * 1000, Vec3::Zero(), k != 0 && k != 3 && k != 4 && k != 9});
  const auto gaps = find_gaps(track);
  ASSERT_EQ(gaps.size(), 3u);
  EXPECT_EQ(gaps[0].t_start_us, -1);
  EXPECT_EQ(gaps[0].t_end_us, 1000);
  EXPECT_EQ(gaps[1].first_occluded, 3u);
  EXPECT_EQ(gaps[1].last_occluded, 4u);
  EXPECT_EQ(gaps[1].t_start_us, 2000);
  EXPECT_EQ(gaps[1].t_end_us, 5000);
  EXPECT_EQ(gaps[2].t_end_us, -1);
}

TEST(GapInput, BoundaryLineIsExactOnLinearMotion) {
  std::vector<TrackSample> track;
  const Vec3 p0(0.1, 0.2, 2.0), v(0.5, -0.3, 0.1);
  for (int k = 0; k < 30; ++k) track.push_back({k * 33'333, p0 + v * (k * 0.033333), true});
  const BoundaryState before = fit_boundary_line(track, 20 * 33'333, -1, 0.5);
  EXPECT_EQ(before.sample_count, 16);
  EXPECT_LT((before.p_K - (p0 + v * (20 * 0.033333))).norm(), 1e-9);
  EXPECT_LT((before.v_K - v).norm(), 1e-9);
  expect_error([&] { fit_boundary_line(track, 40 * 33'333, +1, 0.5); }, ErrorCode::kFailedPrecondition,
               "track.after_gap");
}

TEST(GapInput, NetAccelerationAndSphereAreExactOnTheModel) {
  const ArmMotion motion;
  const GapRecoveryInput in = make_gap_input(motion, noise_free(), 3.0, 1.0, 2.0);
  validate(in);
  const ArmTimeline arm(in);
  for (const ArmSample& s : in.arm) {
    const double t = seconds(s.t_us);
    EXPECT_LT((arm.net_acceleration_K(static_cast<double>(s.t_us)) - motion.acceleration(t)).norm(), 1e-6);
    // eq. 13: the IMU is d_ul from the sphere centre (shoulder interpolated between frames).
    const double radius = (motion.imu_position(t) - arm.sphere_centre_K(static_cast<double>(s.t_us))).norm();
    EXPECT_NEAR(radius, motion.model.d_ul_m, 2e-3);
  }
}

TEST(GapInput, RefusesBadInput) {
  const ArmMotion motion;
  const GapRecoveryInput good = make_gap_input(motion, {}, 3.0, 1.0, 2.0);
  GapRecoveryInput in = good;
  in.track.clear();
  expect_error([&] { validate(in); }, ErrorCode::kInvalidArgument, "track");
  in = good;
  in.arm[5].t_us = in.arm[4].t_us;
  expect_error([&] { validate(in); }, ErrorCode::kInvalidArgument, "arm[5].t_us");
  in = good;
  in.arm[7].specific_force_A.x() = NAN;
  expect_error([&] { validate(in); }, ErrorCode::kInvalidArgument, "arm[7].specific_force_A");
  in = good;
  in.track[2].p_K.y() = NAN;  // visible
  expect_error([&] { validate(in); }, ErrorCode::kInvalidArgument, "track[2].p_K");
  in = good;
  in.shoulder[3].t_us = -5;
  expect_error([&] { validate(in); }, ErrorCode::kInvalidArgument, "shoulder[3].t_us");
  in = good;
  in.model.d_ul_m = 0.0;
  expect_error([&] { validate(in); }, ErrorCode::kInvalidArgument, "model.d_ul_m");
  in = good;
  in.arm[0].K_from_A = Quat(2, 0, 0, 0);
  expect_error([&] { validate(in); }, ErrorCode::kInvalidArgument, "arm[0].K_from_A");
}

}  // namespace
}  // namespace posefuse::forearm
