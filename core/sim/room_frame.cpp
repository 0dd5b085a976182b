#include "sim/room_frame.hpp"

#include "sim/option_checks.hpp"

namespace posefuse::sim {

geometry::Quat W_from_R(double heading_rad) {
  require_finite(heading_rad, "heading_rad");
  Eigen::Matrix3d axes;  // columns: R's axes in W at heading 0
  axes.col(0) = geometry::Vec3::UnitY();
  axes.col(1) = geometry::Vec3::UnitZ();
  axes.col(2) = geometry::Vec3::UnitX();
  return (geometry::Quat(Eigen::AngleAxisd(heading_rad, geometry::Vec3::UnitZ())) * geometry::Quat(axes)).normalized();
}

}  // namespace posefuse::sim
