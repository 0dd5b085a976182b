#pragma once
// One simulated recording for paper 1's Table I (bench_table1): a body motion (the paper's
// protocol or a mocap clip behind a calibration hold) drives the rendered body, the camera SDK
// skeleton and the right forearm's IMU; the base IMU sits on the camera; both IMUs tick on their
// own clocks with noise, the buzzer stop is in the camera audio and BLE receipts are stamped.
// Colour and depth near the forearm come from the strap-test renderer
// (tests/forearm/synthetic_images.hpp: the forearm as a cylinder with the black strap, drawn only
// while the simulator's Embree test says the strap is visible, and the upper arm as a cylinder
// from the shoulder to the elbow), because the simulator has no RGB yet. Kept in this one function so that the
// posefuse-sim CLI can replace it.
#include <cstdint>
#include <vector>

#include "posefuse/v1/session.pb.h"
#include "sim/body_motion.hpp"
#include "sim/forearm_strap.hpp"
#include "sim/frame_truth.hpp"

namespace posefuse::bench {

struct Table1SessionOptions {
  double duration_s = 0.0;         // <= the motion's; 0: the whole motion
  double calibration_end_s = 5.0;  // the stage's forearm.calibration_s (hold ends before it)
  sim::ForearmStrap strap;         // right forearm
  // false: the SDK skeleton without its error model (no bias, jitter, jumps, flips, inferred
  // offsets), to separate the SDK's joint errors from the rest.
  bool sdk_joint_errors = true;
  std::uint64_t seed = 1;
};

struct Table1Session {
  std::vector<v1::SessionChunk> chunks;    // header, data in camera-time order, end marker
  std::vector<std::int64_t> frame_t_us;    // camera clock
  std::vector<sim::ForearmTruth> forearm;  // the right forearm per frame (the "mocap")
  double d_sw_m = 0.0;                     // true strap-to-wrist length (at the first frame)
};

Table1Session simulate_table1_session(const sim::BodyMotion& motion, const Table1SessionOptions& options);

}  // namespace posefuse::bench
