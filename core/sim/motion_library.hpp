#pragma once
// The motions posefuse-sim can play, selected by name: the body's pose sequence plus, for each
// arm, the forearm's pose over time, which the simulator turns into the arm IMU's trajectory
// (mounting F_from_A, strap radius r and strap slip are applied by sim_session).
//
// Extension point: select_motion() is the one place that maps a motion name to what drives the
// body and the IMUs. Body-driven forearm poses, BVH retargeting and the remaining scripted
// exercises plug in here.
#include <array>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "body/pose_parameters.hpp"
#include "sim/camera_session.hpp"
#include "sim/scripted_motion.hpp"

namespace posefuse::sim {

struct MotionOptions {
  double period_s = 4.0;  // one repetition of a periodic exercise
};

// What a motion may need to know about the subject and the scene.
struct MotionContext {
  Eigen::Matrix3Xd rest_joints;      // 3 x 24 SMPL joints of the shaped body, Body frame
  Eigen::Matrix3d W_from_Body = Eigen::Matrix3d::Identity();  // W and Body share the origin
  double heading_rad = 0.0;          // subject's facing in W (see sim_session.hpp)
  double strap_to_elbow_m = 0.15;    // d_se: F's origin on the elbow -> wrist line
};

// The forearm frame F (sim_session.hpp) in W at one instant.
struct ForearmPose {
  Eigen::Matrix3d W_from_F = Eigen::Matrix3d::Identity();
  Vec3 strap_p_W_m = Vec3::Zero();   // F's origin
};

struct SimMotion {
  // The body's DOFs; all_joints() when a motion rolls the forearm (full_body() has no roll).
  body::PoseLayout layout = body::PoseLayout::full_body();
  PoseSequence poses;  // theta of `layout` at camera time t (s)
  // Forearm pose of the left (0) and right (1) arm at camera time t; must agree with `poses`
  // (tests check that the IMU sits on the rendered strap) and be smooth (it is differentiated).
  std::array<std::function<ForearmPose(double t_s)>, 2> forearm;
};

// Names select_motion accepts.
std::vector<std::string> motion_names();

// kInvalidArgument naming "motion" for an unknown name, or the option for a bad value.
SimMotion select_motion(const std::string& name, const MotionOptions& options, const MotionContext& context);

}  // namespace posefuse::sim
