#include "sim/motion_library.hpp"

#include <algorithm>

#include "common/error.hpp"
#include "sim/bvh.hpp"
#include "sim/bvh_motion.hpp"
#include "sim/calibration_prefix.hpp"

namespace posefuse::sim {

namespace {
const char* const kBvhMotion = "bvh";
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
    BodyMotion clip = bvh_motion(load_bvh(options.bvh_path), bvh);
    if (!options.calibration_prefix) return clip;
    return with_calibration_prefix(make_exercise("calibration_pose", options.exercise), clip);
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
