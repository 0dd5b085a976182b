#pragma once
// Scripted whole-body exercises from the papers, as BodyMotions (layout
// PoseLayout::all_joints(), room frame R, see room_frame.hpp and body_pose_angles.hpp):
//
//   calibration_pose           paper 1 Fig. 3b: upper arm sideways and horizontal, forearm
//                              vertical, palm to the camera; held (phase "calibration_hold")
//   forearm_behind_head        paper 1 III: from the calibration pose behind the head and back
//   forearm_in_front_of_belly  paper 1 III: forearm across the belly
//   forearm_behind_back        paper 1 III: hand behind the lower back
//   forearm_protocol           paper 1 III in one take: calibration pose, behind the head,
//                              calibration pose, belly, behind the back, calibration pose
//   arm_raising                paper 2 IV-B: straight arm sideways to 150 deg and down
//   shoulder_lift              paper 2 IV-B: scapular elevation by 20 deg (collar joints)
//   forearm_rolling            paper 2 IV-B: elbow at 90 deg, pronation/supination +-60 deg
//   hair_combing               paper 2 IV-B: hand from the forehead over the head to the back
//   torso_tilt                 paper 2 IV-B: trunk bent 20 deg to the right, then to the left
//   air_punching               paper 2 IV-B: from a guard, punches straight forward
//
// Every motion starts and ends at rest (arms hanging 8 deg away from the body) with a still
// hold, and moves between key poses with C2 ramps (smootherstep of the anatomical angles), so
// angular rates and accelerations are continuous and an IMU on the body reads smooth signals.
// Phases name the intervals where a key pose is held, e.g. "behind_head", "behind_back",
// "in_front_of_belly" (where the forearm is likely occluded from the camera), or a movement is
// repeated ("rolling", "combing", "punch_right").
#include <string>
#include <string_view>
#include <vector>

#include "sim/body_motion.hpp"

namespace posefuse::sim {

enum class ExerciseArm { kRight, kLeft, kBoth };

struct ExerciseOptions {
  ExerciseArm arm = ExerciseArm::kRight;  // air_punching with kBoth alternates the arms
  double speed = 1.0;                     // > 0; 2 halves every movement and hold
  int repetitions = 3;                    // 1..1000 repetitions of the exercise's cycle
  double rest_hold_s = 1.0;               // >= 0, still at rest before and after (not scaled)
};

std::vector<std::string> exercise_names();

// kInvalidArgument naming the field for an unknown name (listing the known ones) or bad
// options.
BodyMotion make_exercise(std::string_view name, const ExerciseOptions& options = {});

}  // namespace posefuse::sim
