#pragma once
// OpenSim marker file (.trc) of a session's joint centres (docs/exports.md, "Markers"): one
// marker per joint (the fitted model's 24 SMPL joints, else the camera's 25), metres, in the
// ground frame, time in seconds on the camera clock (joint_angles.csv's t_s).
#include <cstddef>
#include <ostream>
#include <string>

#include "opensim/ground_frame.hpp"

namespace posefuse::opensim {

struct TrcSummary {
  std::size_t frames = 0;
  std::size_t markers = 0;
  std::size_t missing = 0;  // marker samples written as NaN
  double rate_hz = 0.0;
};

// A joint whose confidence is at most session::kLostFitConfidence (the fit lost tracking) or
// that a frame lacks is written as NaN, which OpenSim's inverse kinematics skips.
// Throws posefuse::Error (kFailedPrecondition) "smpl_joints.csv" with fewer than two frames.
TrcSummary write_trc(const session::ResultDirectory& results, const GroundFrame& ground, const std::string& file_name,
                     std::ostream& out);

}  // namespace posefuse::opensim
