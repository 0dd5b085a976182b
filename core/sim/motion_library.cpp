#include "sim/motion_library.hpp"

#include <cmath>

#include "common/error.hpp"
#include "sim/option_checks.hpp"

namespace posefuse::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

// arm_raising_sequence (camera_session.hpp) turns each arm about the body's forward axis from
// -75 deg (below the T-pose) to +75 deg and back. In the arm chain that is abduction from
// 15 deg (hanging is 0) to 165 deg, in the same plane.
SimMotion arm_raising_motion(const MotionOptions& options, const body::PoseLayout& layout) {
  SimMotion motion;
  motion.poses = arm_raising_sequence(layout, options.period_s);
  const double period = options.period_s;
  const auto angles = [period](double t_s) {
    const double raise = 0.5 * (1.0 - std::cos(2 * kPi * t_s / period));
    ArmAngles a;
    a.shoulder_abduction_rad = kPi / 2 + (-75.0 + 150.0 * raise) * kPi / 180.0;
    return a;
  };
  motion.arm_angles = {angles, angles};
  return motion;
}

}  // namespace

std::vector<std::string> motion_names() { return {"arm_raising"}; }

SimMotion select_motion(const std::string& name, const MotionOptions& options, const body::PoseLayout& layout) {
  require_positive(options.period_s, "motion_period_s");
  if (name == "arm_raising") return arm_raising_motion(options, layout);
  std::string known;
  for (const auto& n : motion_names()) known += (known.empty() ? "" : ", ") + n;
  throw_invalid("motion", "'" + name + "' is not a known motion (known: " + known + ")");
}

}  // namespace posefuse::sim
