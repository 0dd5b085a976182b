#pragma once
// Which vertical a session's thorax angles are read against, and how sure it is (docs/measures.md,
// "The vertical"). Two measure it: the floor that the depth frames show (floor_vertical.hpp) and
// the world's z mapped into the camera by a calibrated IMU's K_from_W. A floor counts only when
// its confidence (from its spread) is at least kConfidentAt. The first one known is
// kept for the rest of the session, so that the thorax angles never step when the other arrives.
// The floor is sought only until one is kept; an IMU's up that arrives after the floor is
// compared with it. Before either, the camera's y is assumed (a level camera) at
// half confidence: nothing measured says how the camera stands, and 0.5 is the bound between
// values to act on and values not to.
#include <cstdint>
#include <optional>

#include "geometry/quaternion.hpp"
#include "measures/floor_vertical.hpp"

namespace posefuse::measures {

enum class VerticalSource { kAssumed, kFloor, kImu };

struct Vertical {
  geometry::Vec3 up_K = geometry::Vec3::UnitY();
  double confidence = 0.5;  // of the thorax angles it gives: the floor's from its spread, the IMU's 1
  VerticalSource source = VerticalSource::kAssumed;
};

class SessionVertical {
 public:
  // Tries for the floor are spaced this far apart on the camera clock while none is kept: one
  // frame's search costs a few milliseconds, and a camera that sees no floor in one frame rarely
  // sees one in the next.
  static constexpr std::int64_t kFloorRetryUs = 1'000'000;

  // Whether a depth frame at t_us should be searched for the floor.
  bool wants_floor(std::int64_t t_us) const;
  // The search's result for the frame at t_us (none: no floor in view).
  void add_floor(std::int64_t t_us, const std::optional<FloorVertical>& floor);
  // The world's up in K from a calibrated IMU (K_from_W * z_W). Non-finite or zero ones are ignored.
  void add_imu_up(const geometry::Vec3& up_K);

  const Vertical& current() const { return current_; }
  const std::optional<FloorVertical>& floor() const { return floor_; }
  const std::optional<geometry::Vec3>& imu_up_K() const { return imu_up_K_; }
  // The angle between the floor's and the IMU's up, rad, when both are known.
  std::optional<double> disagreement_rad() const;

 private:
  Vertical current_;
  std::optional<FloorVertical> floor_;
  std::optional<geometry::Vec3> imu_up_K_;
  std::optional<std::int64_t> last_try_us_;
};

}  // namespace posefuse::measures
