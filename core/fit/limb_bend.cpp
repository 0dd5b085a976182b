#include "fit/limb_bend.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace posefuse::fit {
namespace {

constexpr double kDeg = std::numbers::pi / 180;

bool leg_bent(const TrackedSkeleton& s, int hip, int knee, int ankle, double joint_error_m) {
  for (int j : {hip, knee, ankle})
    if (!joint_unusable_reason(s, j, false).empty()) return false;
  const auto& p = s.positions_K;
  return limb_bend_deg(p[hip], p[knee], p[ankle]) > bend_from_offset_deg(p[hip], p[knee], p[ankle], 2 * joint_error_m);
}

}  // namespace

double limb_bend_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d upper = b - a, lower = c - b;
  return std::atan2(upper.cross(lower).norm(), upper.dot(lower)) / kDeg;
}

double bend_from_offset_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                            double offset_m) {
  return (std::atan2(offset_m, (b - a).norm()) + std::atan2(offset_m, (c - b).norm())) / kDeg;
}

BentLegs camera_bent_legs(const TrackedSkeleton* skeleton, double joint_error_m) {
  if (!skeleton) return {};
  return {leg_bent(*skeleton, kHipLeft, kKneeLeft, kAnkleLeft, joint_error_m),
          leg_bent(*skeleton, kHipRight, kKneeRight, kAnkleRight, joint_error_m)};
}

std::vector<int> held_leg_dofs(const body::PoseLayout& layout, BentLegs bent) {
  std::vector<int> held;
  const auto hold = [&](int joint) {
    for (int d : layout.dofs_of_joint(joint)) held.push_back(d);
  };
  if (!bent.left) {
    hold(body::kLeftKnee);
    hold(body::kLeftAnkle);
  }
  if (!bent.right) {
    hold(body::kRightKnee);
    hold(body::kRightAnkle);
  }
  std::sort(held.begin(), held.end());
  return held;
}

}  // namespace posefuse::fit
