#pragma once
// Stage values (stage_values.hpp) -> the FitResults the client receives (results.proto): the one
// place where the pipeline's typed values meet the wire format.
#include <optional>

#include "posefuse/v1/results.pb.h"
#include "session/stage_values.hpp"

namespace posefuse::session {

// The FitResult for a value the client sees (IMU and forearm orientations, recovered segments,
// frame estimates); none for values that pass only between stages.
std::optional<v1::FitResult> encode_value(const StageValue& value);

}  // namespace posefuse::session
