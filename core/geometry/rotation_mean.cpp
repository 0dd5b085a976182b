#include "geometry/rotation_mean.hpp"

#include <cmath>

namespace posefuse::geometry {

Quat chordal_mean(const std::vector<Quat>& rotations) {
  Vec4 sum = Vec4::Zero();
  for (const Quat& q : rotations) sum += to_wxyz(same_hemisphere(q, rotations.front()));
  return from_wxyz(sum.normalized());
}

double rms_angle_rad(const std::vector<Quat>& rotations, const Quat& mean) {
  double sum_sq = 0.0;
  for (const Quat& q : rotations) sum_sq += std::pow(angle_between(q, mean), 2);
  return std::sqrt(sum_sq / static_cast<double>(rotations.size()));
}

}  // namespace posefuse::geometry
