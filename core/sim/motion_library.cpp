#include "sim/motion_library.hpp"

#include <algorithm>

#include "common/error.hpp"
#include "sim/bvh.hpp"
#include "sim/bvh_glitches.hpp"
#include "sim/bvh_motion.hpp"
#include "sim/calibration_prefix.hpp"
#include "sim/option_checks.hpp"

namespace posefuse::sim {

namespace {
const char* const kBvhMotion = "bvh";

// The motion played `speed` times faster: every instant and phase boundary divided by it.
BodyMotion played_at(BodyMotion motion, double speed) {
  if (speed == 1.0) return motion;
  const PoseSequence poses = motion.poses;
  motion.poses = [poses, speed](double t_s) { return poses(speed * t_s); };
  motion.duration_s /= speed;
  for (MotionPhase& phase : motion.phases) {
    phase.begin_s /= speed;
    phase.end_s /= speed;
  }
  return motion;
}

// An error's message without the "field: " that what() starts with.
std::string message_of(const Error& e) {
  const std::string what = e.what();
  const std::string prefix = e.field() + ": ";
  return what.compare(0, prefix.size(), prefix) == 0 ? what.substr(prefix.size()) : what;
}

// The clip with its mocap glitches repaired (bvh_glitches.hpp), each repair as a warning.
BodyMotion clip_motion(const std::string& path, const BvhGlitchOptions& glitches, const BvhMotionOptions& options) {
  const BvhClip raw = load_bvh(path);
  BvhRepair repaired;
  try {
    repaired = repair_bvh_glitches(raw, glitches, options.joint_map);
  } catch (const Error& e) {
    throw Error(e.code(), path + ": " + e.field(), message_of(e));
  }
  BodyMotion motion;
  try {
    motion = bvh_motion(repaired.clip, options);
  } catch (const Error& e) {  // the rig does not fit the joint map: say which clip
    throw Error(e.code(), e.field(), message_of(e) + " (clip " + path + ")");
  }
  for (const BvhGlitch& glitch : repaired.glitches) {
    motion.warnings.push_back(path + ": " + describe(glitch, raw.frame_time_s));
  }
  return motion;
}

}  // namespace

std::vector<std::string> motion_names() {
  std::vector<std::string> names = exercise_names();
  names.emplace_back(kBvhMotion);
  return names;
}

BodyMotion select_motion(const std::string& name, const MotionOptions& options, const MotionContext& context) {
  if (name == kBvhMotion) {
    if (options.bvh_path.empty()) throw_invalid("bvh_path", "is empty; motion 'bvh' needs a BVH file");
    BvhMotionOptions bvh;
    bvh.sex = context.sex;
    bvh.betas = context.betas;
    bvh.smoothing = options.bvh_smoothing;
    bvh.joint_map = options.bvh_joint_map;
    require_positive(options.exercise.speed, "speed");
    const BodyMotion clip = played_at(clip_motion(options.bvh_path, options.bvh_glitches, bvh), options.exercise.speed);
    BodyMotion motion = clip;
    if (options.calibration_prefix) {
      motion = with_calibration_prefix(make_exercise("calibration_pose", options.exercise), motion);
    }
    if (options.calibration_suffix) {
      ExerciseOptions once = options.exercise;  // one pose at the end, not `repetitions` of them
      once.repetitions = 1;
      motion = with_calibration_suffix(motion, make_exercise("calibration_pose", once));
    }
    return motion;
  }
  const std::vector<std::string> exercises = exercise_names();
  if (std::find(exercises.begin(), exercises.end(), name) == exercises.end()) {
    std::string known;
    for (const auto& n : motion_names()) known += (known.empty() ? "" : ", ") + n;
    throw_invalid("motion", "'" + name + "' is not a known motion (known: " + known + ")");
  }
  return make_exercise(name, options.exercise);
}

}  // namespace posefuse::sim
