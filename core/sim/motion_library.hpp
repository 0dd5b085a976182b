#pragma once
// The motions posefuse-sim can play, selected by name: the body's pose sequence plus the angles
// of the scripted arm chain (scripted_motion.hpp) that moves each arm's IMU the same way.
//
// Extension point: select_motion() is the one place that maps a motion name to what drives the
// body and the IMUs. Body-driven IMU trajectories, BVH retargeting and the remaining scripted
// exercises plug in here.
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "body/pose_parameters.hpp"
#include "sim/camera_session.hpp"
#include "sim/scripted_motion.hpp"

namespace posefuse::sim {

struct MotionOptions {
  double period_s = 4.0;  // one repetition of a periodic exercise
};

struct SimMotion {
  PoseSequence poses;  // theta of PoseLayout::full_body() at camera time t (s)
  // Angles of the scripted arm chain for the left (0) and right (1) arm at camera time t; the
  // IMU of an arm follows its chain. The left arm is the mirror image of a right chain with
  // these angles (see sim_session.hpp).
  std::array<std::function<ArmAngles(double t_s)>, 2> arm_angles;
};

// Names select_motion accepts.
std::vector<std::string> motion_names();

// kInvalidArgument naming "motion" for an unknown name, or the option for a bad value.
SimMotion select_motion(const std::string& name, const MotionOptions& options, const body::PoseLayout& layout);

}  // namespace posefuse::sim
