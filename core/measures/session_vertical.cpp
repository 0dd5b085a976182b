#include "measures/session_vertical.hpp"

#include "geometry/axis_angles.hpp"
#include "measures/joint_angles.hpp"

namespace posefuse::measures {

bool SessionVertical::wants_floor(std::int64_t t_us) const {
  if (current_.source != VerticalSource::kAssumed) return false;
  return !last_try_us_ || t_us >= *last_try_us_ + kFloorRetryUs || t_us < *last_try_us_;
}

void SessionVertical::add_floor(std::int64_t t_us, const std::optional<FloorVertical>& floor) {
  last_try_us_ = t_us;
  if (!floor || current_.source != VerticalSource::kAssumed) return;
  const double confidence = angle_confidence_from_rms_rad(floor->spread_rad);
  // An unsure floor (a small or bent patch) is not kept: it would hold its low confidence for the
  // whole session, though a later frame or the IMU may measure the vertical well.
  if (confidence < kConfidentAt) return;
  floor_ = floor;
  current_ = {floor->up_K, confidence, VerticalSource::kFloor};
}

void SessionVertical::add_imu_up(const geometry::Vec3& up_K) {
  if (imu_up_K_ || !up_K.allFinite() || up_K.norm() < 1e-9) return;
  imu_up_K_ = up_K.normalized();
  if (current_.source == VerticalSource::kAssumed) current_ = {*imu_up_K_, 1.0, VerticalSource::kImu};
}

std::optional<double> SessionVertical::disagreement_rad() const {
  if (!floor_ || !imu_up_K_) return std::nullopt;
  return geometry::angle_between(floor_->up_K, *imu_up_K_);
}

}  // namespace posefuse::measures
