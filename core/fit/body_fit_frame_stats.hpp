#pragma once
// Per fitted frame of the body tracker: where the CPU time went and what the two starts of II-G
// did, for the per-phase benchmark tables and the tests of the start policy.
#include <cstdint>
#include <limits>

#include "fit/frame_observation.hpp"

namespace posefuse::fit {

// Times are CPU seconds of the thread that did the work; a start that was not run has 0
// iterations and a NaN energy.
struct BodyFitFrameStats {
  std::int64_t t_us = 0;
  double assemble_s = 0;         // depth, body index and skeleton into one frame (decoding not counted)
  double cleanup_s = 0;          // fit::remove_off_body_depth
  ObservationTimes observation;  // fit::prepare_observation by part
  double start_pose_s = 0;       // the skeleton-built starting pose (SkeletonPoseInitializer)
  double fit_previous_s = 0;     // LM from the previous frame's pose
  double fit_skeleton_s = 0;     // LM from the skeleton-built pose
  double post_s = 0;             // smoothing, joints, forearm roll, the output frame (not its hand-on)
  int iterations_previous = 0, iterations_skeleton = 0;
  double energy_previous = std::numeric_limits<double>::quiet_NaN();
  double energy_skeleton = std::numeric_limits<double>::quiet_NaN();
  bool previous_won = false;
  bool extrapolated = false;  // the previous-frame fit started from the constant-velocity pose
  double total_s() const {
    return assemble_s + cleanup_s + observation.total_s() + start_pose_s + fit_previous_s + fit_skeleton_s + post_s;
  }
};

}  // namespace posefuse::fit
