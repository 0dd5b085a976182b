#pragma once
// What a stage hands the stages after it: typed values, not wire protos. The pipeline delivers
// each value to the later stages that consume its kind and turns it into the FitResult the
// client receives (result_encoder.hpp), so the wire format is written in one place.
#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "geometry/quaternion.hpp"
#include "imu/imu_sample.hpp"
#include "posefuse/v1/results.pb.h"

namespace posefuse::session {

// The IMU stage's orientation W_from_A for every sample of one IMU batch, beside the samples
// themselves (device clock).
struct ImuOrientations {
  std::string device_id;
  std::vector<imu::ImuSample> samples;
  std::vector<geometry::Quat> W_from_A;  // one per sample
};

// The forearm stage's forearm orientation K_from_F (paper 1 eq. 11) and pronation angle for
// arm IMU samples, on the camera clock, in time order.
struct ForearmOrientations {
  std::string device_id;
  v1::Arm arm = v1::ARM_UNSPECIFIED;
  std::vector<std::int64_t> t_us;
  std::vector<geometry::Quat> K_from_F;
  std::vector<double> pronation_rad;
};

using StageValue = std::variant<ImuOrientations, ForearmOrientations>;

// The kinds, in StageValue's order, for the stages' consumes() and produces().
enum class ValueKind { kImuOrientations, kForearmOrientations };
inline ValueKind kind_of(const StageValue& value) { return static_cast<ValueKind>(value.index()); }
const char* value_kind_name(ValueKind kind);

}  // namespace posefuse::session
