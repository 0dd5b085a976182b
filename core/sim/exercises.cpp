#include "sim/exercises.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>

#include "common/error.hpp"
#include "sim/body_pose_angles.hpp"
#include "sim/option_checks.hpp"

namespace posefuse::sim {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

ArmAngles arm(double abduction_deg, double flexion_deg, double humeral_rotation_deg, double elbow_deg,
              double supination_deg = 0.0) {
  ArmAngles a;
  a.shoulder_abduction_rad = abduction_deg * kDeg;
  a.shoulder_flexion_rad = flexion_deg * kDeg;
  a.humeral_rotation_rad = humeral_rotation_deg * kDeg;
  a.elbow_flexion_rad = elbow_deg * kDeg;
  a.supination_rad = supination_deg * kDeg;
  return a;
}

// Key arm poses (right arm; the left one mirrors them): angles found by a grid search (5-10 deg
// steps) that puts the default male template's elbow and wrist closest to target positions
// (behind the head: upper arm almost vertical, forearm across the back of the head at its
// height, wrist 12 cm behind the skull-base joint; behind the
// back: wrist behind the lower back at the midline; combing: hand above the forehead, then
// above the back of the head; guard: fist in front of the chin). Checked in
// tests/sim/exercises_test.
ArmAngles hanging() { return arm(8, 0, 0, 0); }
ArmAngles calibration() { return arm(90, 0, 90, 90); }  // paper 1 Fig. 3b
ArmAngles behind_head() { return arm(175, -10, 110, 100); }
ArmAngles in_front_of_belly() { return arm(12, 20, -80, 95); }
ArmAngles behind_back() { return arm(15, -35, -90, 75); }
ArmAngles raised() { return arm(150, 0, 0, 0); }
ArmAngles forearm_forward(double supination_deg) { return arm(8, 0, 0, 90, supination_deg); }
ArmAngles comb_front() { return arm(150, 35, 90, 105); }
ArmAngles comb_back() { return arm(155, -10, 100, 105); }
ArmAngles guard() { return arm(15, 30, -10, 135); }
ArmAngles punch() { return arm(5, 90, 0, 5, -90); }

// One straight piece of the timeline: from `from` to `to` over duration_s with a C2 ramp (a
// hold when both are equal), optionally named as a phase.
struct Segment {
  BodyPoseAngles from, to;
  double begin_s = 0.0, duration_s = 0.0;
  std::string phase;
};

class Timeline {
 public:
  explicit Timeline(BodyPoseAngles start) : current_(start) {}
  void move(const BodyPoseAngles& to, double duration_s, const std::string& phase = "") {
    segments_.push_back({current_, to, end_s_, duration_s, phase});
    end_s_ += duration_s;
    current_ = to;
  }
  void hold(double duration_s, const std::string& phase = "") { move(current_, duration_s, phase); }
  const BodyPoseAngles& current() const { return current_; }

  BodyMotion finish() && {
    BodyMotion motion;
    motion.duration_s = end_s_;
    for (const Segment& s : segments_) {
      if (s.phase.empty()) continue;
      // Consecutive segments of one phase form one interval.
      if (!motion.phases.empty() && motion.phases.back().name == s.phase &&
          std::abs(motion.phases.back().end_s - s.begin_s) < 1e-12) {
        motion.phases.back().end_s = s.begin_s + s.duration_s;
      } else {
        motion.phases.push_back({s.phase, s.begin_s, s.begin_s + s.duration_s});
      }
    }
    auto segments = std::make_shared<const std::vector<Segment>>(std::move(segments_));
    motion.poses = [segments](double t_s) {
      const std::vector<Segment>& all = *segments;
      // The last segment starting at or before t (held before the first and after the last).
      const auto it =
          std::upper_bound(all.begin(), all.end(), t_s, [](double t, const Segment& s) { return t < s.begin_s; });
      const Segment& s = it == all.begin() ? all.front() : *(it - 1);
      const double w = s.duration_s > 0 ? smootherstep((t_s - s.begin_s) / s.duration_s) : 1.0;
      return all_joints_theta(blend(s.from, s.to, w));
    };
    return motion;
  }

 private:
  BodyPoseAngles current_;
  std::vector<Segment> segments_;
  double end_s_ = 0.0;
};

BodyPoseAngles rest_pose() {
  BodyPoseAngles p;
  p.right_arm = hanging();
  p.left_arm = hanging();
  return p;
}

// The rest pose with the chosen arm(s) in `a`.
BodyPoseAngles with_arm(const ArmAngles& a, ExerciseArm side) {
  BodyPoseAngles p = rest_pose();
  if (side != ExerciseArm::kLeft) p.right_arm = a;
  if (side != ExerciseArm::kRight) p.left_arm = a;
  return p;
}

// Builds one exercise: `cycle` appends one repetition to the timeline; times are already
// divided by the speed through `s` (seconds at speed 1 -> seconds).
using CycleBuilder = std::function<void(Timeline&, const ExerciseOptions&, const std::function<double(double)>& s)>;

struct ExerciseDef {
  const char* name;
  CycleBuilder lead_in;  // from rest into the exercise's start pose (may be empty)
  CycleBuilder cycle;
};

using Seconds = std::function<double(double)>;

void to_calibration(Timeline& t, const ExerciseOptions& o, const Seconds& s) {
  t.move(with_arm(calibration(), o.arm), s(1.5));
  t.hold(s(1.0), "calibration_hold");
}

// Moves the arm(s) to `pose` and holds it; the hold is named `phase`.
void reach(Timeline& t, const ExerciseOptions& o, const Seconds& s, const ArmAngles& pose, const std::string& phase,
           double hold_s) {
  t.move(with_arm(pose, o.arm), s(1.5));
  t.hold(s(hold_s), phase);
}

void back_to_calibration(Timeline& t, const ExerciseOptions& o, const Seconds& s, double move_s) {
  t.move(with_arm(calibration(), o.arm), s(move_s));
  t.hold(s(0.5), "calibration_hold");
}

// Paper 1, III: from the calibration pose behind the head and back.
void behind_head_cycle(Timeline& t, const ExerciseOptions& o, const Seconds& s) {
  reach(t, o, s, behind_head(), "behind_head", 1.0);
  back_to_calibration(t, o, s, 1.5);
}

// Paper 1, III: in front of the belly, on behind the back, back to the calibration pose.
void behind_back_cycle(Timeline& t, const ExerciseOptions& o, const Seconds& s) {
  reach(t, o, s, in_front_of_belly(), "in_front_of_belly", 0.5);
  reach(t, o, s, behind_back(), "behind_back", 1.0);
  back_to_calibration(t, o, s, 2.0);
}

const std::vector<ExerciseDef>& definitions() {
  static const std::vector<ExerciseDef> defs = {
      {"calibration_pose", nullptr,
       [](Timeline& t, const ExerciseOptions& o, const auto& s) {
         t.move(with_arm(calibration(), o.arm), s(1.5));
         t.hold(s(3.0), "calibration_hold");
         t.move(rest_pose(), s(1.5));
         t.hold(s(0.5));
       }},
      {"forearm_behind_head", to_calibration, behind_head_cycle},
      {"forearm_in_front_of_belly", to_calibration,
       [](Timeline& t, const ExerciseOptions& o, const auto& s) {
         reach(t, o, s, in_front_of_belly(), "in_front_of_belly", 1.0);
         back_to_calibration(t, o, s, 1.5);
       }},
      {"forearm_behind_back", to_calibration, behind_back_cycle},
      {"forearm_protocol", to_calibration,
       [](Timeline& t, const ExerciseOptions& o, const auto& s) {
         behind_head_cycle(t, o, s);
         behind_back_cycle(t, o, s);
       }},
      {"arm_raising", nullptr,
       [](Timeline& t, const ExerciseOptions& o, const auto& s) {
         t.move(with_arm(raised(), o.arm), s(2.0), "raising");
         t.hold(s(0.5), "raised");
         t.move(rest_pose(), s(2.0), "lowering");
         t.hold(s(0.5));
       }},
      {"shoulder_lift", nullptr,
       [](Timeline& t, const ExerciseOptions& o, const auto& s) {
         BodyPoseAngles lifted = rest_pose();
         if (o.arm != ExerciseArm::kLeft) lifted.right_scapular_elevation_rad = 20 * kDeg;
         if (o.arm != ExerciseArm::kRight) lifted.left_scapular_elevation_rad = 20 * kDeg;
         t.move(lifted, s(1.0));
         t.hold(s(1.0), "lifted");
         t.move(rest_pose(), s(1.0));
         t.hold(s(0.5));
       }},
      {"forearm_rolling",
       [](Timeline& t, const ExerciseOptions& o, const auto& s) {
         t.move(with_arm(forearm_forward(0), o.arm), s(1.5));
       },
       [](Timeline& t, const ExerciseOptions& o, const auto& s) {
         t.move(with_arm(forearm_forward(60), o.arm), s(0.5), "rolling");
         t.move(with_arm(forearm_forward(-60), o.arm), s(1.0), "rolling");
         t.move(with_arm(forearm_forward(0), o.arm), s(0.5), "rolling");
       }},
      {"hair_combing",
       [](Timeline& t, const ExerciseOptions& o, const auto& s) { t.move(with_arm(comb_front(), o.arm), s(1.5)); },
       [](Timeline& t, const ExerciseOptions& o, const auto& s) {
         t.move(with_arm(comb_back(), o.arm), s(1.2), "combing");
         t.move(with_arm(comb_front(), o.arm), s(1.2), "combing");
       }},
      {"torso_tilt", nullptr,
       [](Timeline& t, const ExerciseOptions&, const auto& s) {
         BodyPoseAngles right = rest_pose(), left = rest_pose();
         right.trunk_lateral_tilt_rad = 20 * kDeg;
         left.trunk_lateral_tilt_rad = -20 * kDeg;
         t.move(right, s(1.5));
         t.hold(s(0.5), "tilt_right");
         t.move(left, s(3.0));
         t.hold(s(0.5), "tilt_left");
         t.move(rest_pose(), s(1.5));
         t.hold(s(0.5));
       }},
      {"air_punching",
       [](Timeline& t, const ExerciseOptions&, const auto& s) {
         t.move(with_arm(guard(), ExerciseArm::kBoth), s(1.0));
       },
       [](Timeline& t, const ExerciseOptions& o, const auto& s) {
         const BodyPoseAngles both_guard = with_arm(guard(), ExerciseArm::kBoth);
         auto punch_with = [&](ExerciseArm side) {
           BodyPoseAngles p = both_guard;
           (side == ExerciseArm::kRight ? p.right_arm : p.left_arm) = punch();
           t.move(p, s(0.35), side == ExerciseArm::kRight ? "punch_right" : "punch_left");
           t.move(both_guard, s(0.45));
         };
         if (o.arm == ExerciseArm::kBoth) {
           punch_with(ExerciseArm::kRight);
           punch_with(ExerciseArm::kLeft);
         } else {
           punch_with(o.arm);
         }
       }},
  };
  return defs;
}

}  // namespace

std::vector<std::string> exercise_names() {
  std::vector<std::string> names;
  for (const ExerciseDef& d : definitions()) names.emplace_back(d.name);
  return names;
}

BodyMotion make_exercise(std::string_view name, const ExerciseOptions& options) {
  require_positive(options.speed, "speed");
  require_non_negative(options.rest_hold_s, "rest_hold_s");
  if (options.repetitions < 1 || options.repetitions > 1000) {
    throw_invalid("repetitions", "must be in 1..1000, got " + std::to_string(options.repetitions));
  }
  const auto& defs = definitions();
  const auto def = std::find_if(defs.begin(), defs.end(), [&](const ExerciseDef& d) { return name == d.name; });
  if (def == defs.end()) {
    std::string known;
    for (const ExerciseDef& d : defs) known += std::string(known.empty() ? "" : ", ") + d.name;
    throw_invalid("exercise", "unknown exercise '" + std::string(name) + "'; known: " + known);
  }
  const auto scaled = [&options](double seconds) { return seconds / options.speed; };
  Timeline t(rest_pose());
  t.hold(options.rest_hold_s);
  if (def->lead_in) def->lead_in(t, options, scaled);
  for (int r = 0; r < options.repetitions; ++r) def->cycle(t, options, scaled);
  if (def->lead_in) {  // back to rest from the exercise's own start pose
    t.move(rest_pose(), scaled(1.5));
  }
  t.hold(options.rest_hold_s);
  return std::move(t).finish();
}

}  // namespace posefuse::sim
