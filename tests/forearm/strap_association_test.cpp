// Which arm a strap found in a frame belongs to (arm_frame_measurement.hpp,
// drop_straps_nearer_another_wrist): each arm keeps the strap nearer its own SDK wrist.
#include <gtest/gtest.h>

#include "forearm/arm_frame_measurement.hpp"

namespace posefuse::forearm {
namespace {

ArmFrame arm_with_wrist(const Vec3& sdk_wrist_K, const std::optional<Vec3>& strap_K) {
  ArmFrame arm;
  arm.forearm_tracked = true;
  arm.sdk_wrist_K = sdk_wrist_K;
  arm.wrist_K = sdk_wrist_K;
  arm.strap_K = strap_K;
  return arm;
}

// Hands together in front of the belly: the right arm's search ran on over the left forearm and
// found the left band, 8 cm from the left SDK wrist and 18 cm from the right one.
TEST(StrapAssociation, StrapAtTheOtherWristIsDropped) {
  std::vector<ArmFrame> arms{arm_with_wrist({-0.05, 0.15, 2.35}, Vec3(-0.09, 0.16, 2.35)),
                             arm_with_wrist({0.05, 0.15, 2.35}, Vec3(-0.13, 0.14, 2.37))};
  EXPECT_EQ(drop_straps_nearer_another_wrist(arms), 1u);
  EXPECT_TRUE(arms[0].strap_K.has_value());
  EXPECT_FALSE(arms[1].strap_K.has_value());
}

TEST(StrapAssociation, EachArmsOwnStrapIsKept) {
  std::vector<ArmFrame> arms{arm_with_wrist({-0.30, 0.0, 2.3}, Vec3(-0.27, 0.02, 2.3)),
                             arm_with_wrist({0.30, 0.0, 2.3}, Vec3(0.26, 0.01, 2.3))};
  EXPECT_EQ(drop_straps_nearer_another_wrist(arms), 0u);
  EXPECT_TRUE(arms[0].strap_K && arms[1].strap_K);
}

// The other arm's wrist only counts where the SDK tracks that forearm; one arm alone keeps its strap.
TEST(StrapAssociation, UntrackedOrAbsentOtherArmDropsNothing) {
  std::vector<ArmFrame> arms{arm_with_wrist({-0.05, 0.15, 2.35}, std::nullopt),
                             arm_with_wrist({0.05, 0.15, 2.35}, Vec3(-0.13, 0.14, 2.37))};
  arms[0].forearm_tracked = false;
  EXPECT_EQ(drop_straps_nearer_another_wrist(arms), 0u);
  EXPECT_TRUE(arms[1].strap_K.has_value());
  std::vector<ArmFrame> right_alone{arms[1]};
  EXPECT_EQ(drop_straps_nearer_another_wrist(right_alone), 0u);
  EXPECT_TRUE(right_alone[0].strap_K.has_value());
  std::vector<ArmFrame> none;
  EXPECT_EQ(drop_straps_nearer_another_wrist(none), 0u);
}

}  // namespace
}  // namespace posefuse::forearm
