#pragma once
// Per-frame errors of one Table I session (paper 1, III): the camera SDK against the fusion
// (the forearm stage's results), against the simulator's forearm truth.
#include <cstdint>
#include <string>
#include <vector>

#include "eval/forearm_errors.hpp"
#include "posefuse/v1/results.pb.h"
#include "posefuse/v1/session.pb.h"
#include "sim/frame_truth.hpp"

namespace posefuse::bench {

// One value per camera frame; NaN where a method gives no estimate at that frame.
struct Table1Series {
  std::vector<double> t_s;
  std::vector<bool> occluded;                  // the truth's occlusion flag (strap hidden)
  std::vector<double> sdk_orientation_deg;     // eqs. 14-15, SDK wrist orientation
  std::vector<double> fusion_orientation_deg;  // eqs. 14-15, FrameResult.forearms (eq. 11)
  // IMU position error, m: SDK by eq. 16; fusion = eq. 10 where the strap is seen, inside gaps
  // the PAPER / SMOOTHER recovered segment (linear between its 80 Hz samples) or the causal
  // live estimate (PREDICTED).
  std::vector<double> sdk_position_m, paper_position_m, smoother_position_m, live_position_m;
  // x_K of the IMU (paper 1, Fig. 6): truth, SDK, paper, smoother.
  std::vector<double> true_x_m, sdk_x_m, paper_x_m, smoother_x_m;
  std::size_t sdk_orientation_missing = 0;  // frames whose wrist had no SDK orientation
  std::vector<bool> stage_visible;          // the stage gave an eq. 10 (VISUAL) position
};

// The arm scored: the stage's results for it (ForearmOrientation and RecoveredSegment by arm,
// ImuPosition by device_id) and the SDK's elbow and wrist of that side.
struct Table1Arm {
  v1::Arm arm = v1::RIGHT;
  std::string device_id;
  double d_se_m = 0.0, d_sw_m = 0.0;  // eq. 16's lengths
};

// What the session gives per camera frame: its times, the scored arm's truth (the "mocap"; its
// `occluded` selects the gap frames) and the SDK skeletons (matched to frames by t_us).
struct Table1Truth {
  std::vector<std::int64_t> frame_t_us;
  std::vector<sim::ForearmTruth> forearm;
  std::vector<v1::SkeletonFrame> sdk;
};

// The SDK's wrist frame has the SDK's axis convention, not F's: its constant offset is taken as
// the chordal mean of SDK^-1 * truth over the calibration hold [hold_begin_s, hold_end_s]
// (a favour to the SDK: paper 1 uses the SDK orientation there as K_from_F', eq. 9).
Table1Series table1_series(const Table1Truth& truth, const std::vector<v1::FitResult>& results, const Table1Arm& arm,
                           double hold_begin_s, double hold_end_s);

}  // namespace posefuse::bench
