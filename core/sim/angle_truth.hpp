#pragma once
// The true ISB joint angles and repetitions of a simulated session (gt/joint_angles.csv,
// gt/repetitions.csv): measures/joint_angles.hpp applied to the true SMPL joints of every frame,
// the true vertical (K_from_W) and, on arms with an IMU, the true forearm frame's thumb axis; the
// repetitions by measures/angle_series.hpp on the true angles. The same construction as the
// server's, on the simulator's own segment poses, not on posefuse's estimates.
#include <vector>

#include "measures/angle_series.hpp"
#include "sim/sim_session.hpp"

namespace posefuse::sim {

struct AngleTruth {
  std::vector<measures::JointAngles> frames;  // one per SimTruth::frames entry
  std::optional<measures::SessionRepetitions> repetitions;
};

AngleTruth angle_truth(const SimTruth& truth, const measures::JointAngleOptions& angle_options = {},
                       const measures::RepetitionOptions& repetition_options = {});

}  // namespace posefuse::sim
