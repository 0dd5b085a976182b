#pragma once
// OpenSim motion file (.mot) of a session's ISB joint angles (docs/exports.md, "Joint angles"):
// time in seconds (joint_angles.csv's t_s), one column per angle named as in joint_angles.csv
// (docs/measures.md), inDegrees=yes.
#include <cstddef>
#include <ostream>
#include <string>

#include "session/result_reader.hpp"

namespace posefuse::opensim {

struct MotSummary {
  std::size_t rows = 0;
  std::size_t columns = 0;  // angles, time not counted
  std::size_t missing = 0;  // values written as NaN
};

// An angle that is undefined, or defined with confidence 0 (the held plane of elevation), is
// written as NaN. Throws posefuse::Error (kFailedPrecondition) "joint_angles.csv" without angles.
MotSummary write_mot(const session::ResultDirectory& results, const std::string& name, std::ostream& out);

}  // namespace posefuse::opensim
