// Constant-velocity start of the previous-frame fit (fit/start_extrapolation.hpp, ours, issue 7).
#include "fit/start_extrapolation.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <numbers>

#include "common/error.hpp"

namespace posefuse::fit {
namespace {

constexpr double kDeg = std::numbers::pi / 180;
constexpr std::int64_t kFrameUs = 40'000;  // 25 Hz: the gaps below are whole microseconds

struct Track {
  body::PoseLayout layout = body::PoseLayout::upper_body();
  Eigen::VectorXd first = Eigen::VectorXd::Constant(layout.size(), 0.1);
  // Every rotation DOF turns by 3 deg per frame, the translation moves 1 cm per frame.
  Eigen::VectorXd velocity() const {
    Eigen::VectorXd v(layout.size());
    for (int d = 0; d < layout.size(); ++d) v[d] = layout.dof(d).kind == body::DofKind::kTranslation ? 0.01 : 3 * kDeg;
    return v;
  }
};

TEST(StartExtrapolation, ContinuesAConstantVelocity) {
  const Track track;
  const FittedPose a{track.first, 0}, b{track.first + track.velocity(), kFrameUs};
  const auto start = extrapolate_start(track.layout, a, b, 2 * kFrameUs);
  ASSERT_TRUE(start.has_value());
  EXPECT_LT((*start - (track.first + 2 * track.velocity())).cwiseAbs().maxCoeff(), 1e-12);
  // A frame that comes after a dropped one (twice the gap) is moved twice as far.
  const auto later = extrapolate_start(track.layout, a, b, kFrameUs + kFrameUs * 14 / 10);
  ASSERT_TRUE(later.has_value());
  EXPECT_LT((*later - (track.first + 2.4 * track.velocity())).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(StartExtrapolation, GainScalesTheVelocity) {
  const Track track;
  StartExtrapolationOptions half;
  half.velocity_gain = 0.5;
  const auto start =
      extrapolate_start(track.layout, {track.first, 0}, {track.first + track.velocity(), kFrameUs}, 2 * kFrameUs, half);
  ASSERT_TRUE(start.has_value());
  EXPECT_LT((*start - (track.first + 1.5 * track.velocity())).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(StartExtrapolation, FallsBackOnAJump) {
  const Track track;
  const int elbow = track.layout.dofs_of_joint(body::kLeftElbow).front();
  Eigen::VectorXd jumped = track.first + track.velocity();
  jumped[elbow] += 25 * kDeg;  // a skeleton-start win or a lost limb, not motion
  EXPECT_FALSE(extrapolate_start(track.layout, {track.first, 0}, {jumped, kFrameUs}, 2 * kFrameUs).has_value());
  Eigen::VectorXd moved = track.first + track.velocity();
  moved[0] += 0.2;  // 20 cm of translation in one frame
  EXPECT_FALSE(extrapolate_start(track.layout, {track.first, 0}, {moved, kFrameUs}, 2 * kFrameUs).has_value());
  // The same change spread over five frames is motion: it is extrapolated.
  Eigen::VectorXd slow = track.first;
  slow[elbow] += 25 * kDeg;
  EXPECT_TRUE(extrapolate_start(track.layout, {track.first, 0}, {slow, 5 * kFrameUs}, 6 * kFrameUs).has_value());
}

TEST(StartExtrapolation, FallsBackOnAGapOrTimesOutOfOrder) {
  const Track track;
  const FittedPose a{track.first, 0}, b{track.first + track.velocity(), kFrameUs};
  EXPECT_FALSE(extrapolate_start(track.layout, a, b, kFrameUs + 2 * kFrameUs).has_value());  // gap 2x > 1.5x
  EXPECT_FALSE(extrapolate_start(track.layout, a, b, kFrameUs).has_value());                 // same time
  EXPECT_FALSE(extrapolate_start(track.layout, b, a, 2 * kFrameUs).has_value());             // out of order
}

TEST(StartExtrapolation, BadInputIsAnErrorNamingTheField) {
  const Track track;
  const FittedPose a{track.first, 0}, b{track.first, kFrameUs};
  const FittedPose short_pose{Eigen::VectorXd::Zero(3), kFrameUs};
  try {
    extrapolate_start(track.layout, a, short_pose, 2 * kFrameUs);
    FAIL() << "a pose of the wrong size was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "theta");
  }
  StartExtrapolationOptions bad;
  bad.max_rotation_rad = std::numeric_limits<double>::quiet_NaN();
  try {
    extrapolate_start(track.layout, a, b, 2 * kFrameUs, bad);
    FAIL() << "a NaN option was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "start_extrapolation.max_rotation_rad");
  }
}

}  // namespace
}  // namespace posefuse::fit
