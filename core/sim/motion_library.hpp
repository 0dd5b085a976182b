#pragma once
// The motions posefuse-sim can play, selected by name: a whole-body motion (BodyMotion) that
// drives the rendered body, the camera skeleton and, through the posed forearm
// (forearm_strap.hpp), the arm IMUs. sim_session poses the skeleton at 1 kHz and puts each IMU
// on its strap (mounting F_from_A, strap radius r and strap slip are applied there).
//
// select_motion() is the one place that maps a motion name to a BodyMotion: every scripted
// exercise of exercises.hpp by its name, and "bvh" for a BVH clip (bvh_motion.hpp) retargeted
// onto the subject. Both use PoseLayout::all_joints(), so forearm roll (pronation/supination)
// reaches the rendered forearm, the strap and the IMU.
#include <string>
#include <vector>

#include <Eigen/Core>

#include "body/template_generator.hpp"
#include "sim/body_motion.hpp"
#include "sim/bvh_glitches.hpp"
#include "sim/bvh_joint_map.hpp"
#include "sim/bvh_motion.hpp"
#include "sim/exercises.hpp"

namespace posefuse::sim {

struct MotionOptions {
  ExerciseOptions exercise;  // arm, speed, repetitions, rest hold (speed also plays a BVH clip faster)
  std::string bvh_path;      // motion "bvh": the clip to play, its glitches repaired (bvh_glitches.hpp)
  // Motion "bvh": play the calibration_pose exercise (with exercise.arm) up to the end of its
  // hold first and blend into the clip (calibration_prefix.hpp): the forearm stage needs paper
  // 1's calibration pose (II-H), which a mocap clip does not start in.
  bool calibration_prefix = false;
  // Motion "bvh": the calibration_pose exercise, once, after the clip, blended in (a session whose
  // calibration pose comes last; calibration_prefix.hpp).
  bool calibration_suffix = false;
  BvhSmoothing bvh_smoothing = BvhSmoothing::kGaussian;  // motion "bvh" (bvh_motion.hpp)
  BvhGlitchOptions bvh_glitches;                         // motion "bvh" (bvh_glitches.hpp)
  BvhJointMap bvh_joint_map = auto_bvh_joint_map();      // motion "bvh" (bvh_joint_map.hpp)
};

// What a motion may need to know about the subject.
struct MotionContext {
  body::Sex sex = body::Sex::kMale;
  Eigen::VectorXd betas = Eigen::VectorXd::Zero(body::kTemplateNumBetas);
};

// Names select_motion accepts: exercise_names() and "bvh".
std::vector<std::string> motion_names();

// The motion's poses (PoseLayout::all_joints()), its own duration and phases. kInvalidArgument
// naming "motion" for an unknown name, "bvh_path" when a bvh motion has none, or the option
// (speed, repetitions, ...) for a bad value; load_bvh's errors for unreadable or malformed files;
// for a clip with an unrepairable glitch, repair_bvh_glitches' error with the path before its
// field ("<path>: bvh.frames[a..b]"). Repaired glitches are in BodyMotion::warnings.
BodyMotion select_motion(const std::string& name, const MotionOptions& options, const MotionContext& context);

}  // namespace posefuse::sim
