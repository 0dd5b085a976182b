#include "sim/exercises.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "body/pose_parameters.hpp"
#include "body/smpl_model.hpp"
#include "common/error.hpp"
#include "sim/body_pose_angles.hpp"
#include "sim/calibration_prefix.hpp"
#include "sim/forearm_strap.hpp"
#include "sim/skeleton_pose.hpp"

using posefuse::Error;
using namespace posefuse::sim;
namespace body = posefuse::body;

namespace {

using std::numbers::pi;

const Eigen::Matrix3Xd& rest_joints() {
  static const Eigen::Matrix3Xd rest = template_rest_joints(body::Sex::kMale, Eigen::VectorXd::Zero(10));
  return rest;
}

SkeletonPose pose_at(const BodyMotion& motion, double t) {
  return pose_skeleton(rest_joints(), body::PoseLayout::all_joints(), motion.poses(t));
}

const MotionPhase& phase(const BodyMotion& motion, const std::string& name) {
  for (const MotionPhase& p : motion.phases) {
    if (p.name == name) return p;
  }
  throw std::runtime_error("no phase " + name);
}

double middle(const MotionPhase& p) { return 0.5 * (p.begin_s + p.end_s); }

double elevation_deg(const Vec3& v) { return std::asin(v.normalized().y()) * 180.0 / pi; }

Vec3 joint(const SkeletonPose& p, int j) { return p.joints.col(j); }

// The rotation vector that paper 2's limit table (eq. 8) bounds for joint j. The table limits
// every axis of the spine and head, but only two axes of the limbs: their third axis runs
// along the bone and is the roll that all_joints adds (forearm pronation/supination). For those
// the limits apply to the swing part of the local rotation q = swing * twist (twist about the
// bone axis), because a roll composed with a flexion moves the other rotation-vector components
// without moving the bone.
Vec3 limited_rotation(const body::PoseLayout& layout, const Eigen::VectorXd& theta, int j) {
  const Vec3 omega = theta.segment<3>(all_joints_rotation_index(j));
  int free_axis = -1;
  for (int a = 0; a < 3; ++a) {
    if (!layout.dof(all_joints_rotation_index(j) + a).limited) free_axis = a;
  }
  if (free_axis < 0) return omega;
  const Quat q = posefuse::geometry::quat_from_rotation_vector(omega);
  Eigen::Vector4d twist_coeffs = Eigen::Vector4d::Zero();  // x y z w
  twist_coeffs[free_axis] = q.vec()[free_axis];
  twist_coeffs[3] = q.w();
  if (twist_coeffs.norm() < 1e-12) return omega;  // a half turn about an axis across the bone
  const Quat twist(twist_coeffs[3], twist_coeffs[0], twist_coeffs[1], twist_coeffs[2]);
  return posefuse::geometry::rotation_vector_from_quat(q * twist.normalized().conjugate());
}

}  // namespace

TEST(Exercises, RegistryListsThePapersExercises) {
  const std::vector<std::string> names = exercise_names();
  for (const char* expected : {"calibration_pose", "forearm_behind_head", "forearm_in_front_of_belly",
                               "forearm_behind_back", "forearm_protocol", "arm_raising", "shoulder_lift",
                               "forearm_rolling", "hair_combing", "torso_tilt", "air_punching"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
  }
  try {
    make_exercise("juggling");
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "exercise");
    EXPECT_NE(std::string(e.what()).find("hair_combing"), std::string::npos);
  }
  ExerciseOptions bad;
  bad.speed = 0;
  EXPECT_THROW(make_exercise("arm_raising", bad), Error);
  bad = {};
  bad.repetitions = 0;
  EXPECT_THROW(make_exercise("arm_raising", bad), Error);
  bad = {};
  bad.rest_hold_s = std::nan("");
  EXPECT_THROW(make_exercise("arm_raising", bad), Error);
}

// Every exercise, every arm choice: finite poses of the all_joints size, within the soft joint
// limits of paper 2's eq. 8 table wherever the table has a limit (see limited_rotation), starting and ending at rest,
// with phases inside the motion, and the same numbers twice.
TEST(Exercises, PosesAreFiniteWithinLimitsAndDeterministic) {
  const body::PoseLayout layout = body::PoseLayout::all_joints();
  const double tolerance = 1e-9;
  for (const std::string& name : exercise_names()) {
    for (ExerciseArm arm : {ExerciseArm::kRight, ExerciseArm::kLeft, ExerciseArm::kBoth}) {
      ExerciseOptions options;
      options.arm = arm;
      options.repetitions = 2;
      const BodyMotion motion = make_exercise(name, options);
      const BodyMotion again = make_exercise(name, options);
      ASSERT_GT(motion.duration_s, 2.0) << name;
      EXPECT_EQ(motion.poses(0.0), motion.poses(motion.duration_s)) << name;  // rest at both ends
      for (const MotionPhase& p : motion.phases) {
        EXPECT_LE(0.0, p.begin_s);
        EXPECT_LT(p.begin_s, p.end_s);
        EXPECT_LE(p.end_s, motion.duration_s);
      }
      for (double t = 0.0; t <= motion.duration_s; t += 0.01) {
        const Eigen::VectorXd theta = motion.poses(t);
        ASSERT_EQ(theta.size(), layout.size());
        ASSERT_TRUE(theta.allFinite()) << name << " t=" << t;
        EXPECT_EQ(theta, again.poses(t));
        for (int j = 1; j < body::kNumJoints; ++j) {
          const Vec3 limited = limited_rotation(layout, theta, j);
          for (int a = 0; a < 3; ++a) {
            const body::Dof& dof = layout.dof(all_joints_rotation_index(j) + a);
            if (!dof.limited) continue;
            EXPECT_GE(limited[a], dof.min_rad - tolerance) << name << " " << dof.name << " t=" << t;
            EXPECT_LE(limited[a], dof.max_rad + tolerance) << name << " " << dof.name << " t=" << t;
          }
        }
      }
    }
  }
}

// Paper 1, Fig. 3b: upper arm sideways and horizontal, forearm vertical, hand up, palm to the
// camera (the subject faces +z), both in the coronal plane.
TEST(Exercises, CalibrationPoseGeometry) {
  for (BodySide side : {BodySide::kRight, BodySide::kLeft}) {
    ExerciseOptions options;
    options.arm = side == BodySide::kRight ? ExerciseArm::kRight : ExerciseArm::kLeft;
    const BodyMotion motion = make_exercise("calibration_pose", options);
    const SkeletonPose p = pose_at(motion, middle(phase(motion, "calibration_hold")));
    const bool right = side == BodySide::kRight;
    const int shoulder = right ? body::kRightShoulder : body::kLeftShoulder;
    const int elbow = right ? body::kRightElbow : body::kLeftElbow;
    const int wrist = right ? body::kRightWrist : body::kLeftWrist;
    const Vec3 upper = joint(p, elbow) - joint(p, shoulder), fore = joint(p, wrist) - joint(p, elbow);
    EXPECT_NEAR(elevation_deg(upper), 0.0, 2.0);
    EXPECT_NEAR(elevation_deg(fore), 90.0, 2.0);
    EXPECT_NEAR(upper.normalized().x(), right ? -1.0 : 1.0, 1e-3);  // sideways, outwards
    const ForearmStrap strap{side};
    const ForearmPose f = forearm_pose(p, forearm_rest_R_from_F(rest_joints(), side), strap);
    const Vec3 dorsal = f.R_from_F * Vec3::UnitX();
    EXPECT_LT(std::acos(std::clamp(-dorsal.z(), -1.0, 1.0)) * 180 / pi, 2.0) << "palm faces +z";
    const Vec3 thumb = (right ? 1.0 : -1.0) * (f.R_from_F * Vec3::UnitZ());
    EXPECT_NEAR(thumb.x(), right ? 1.0 : -1.0, 1e-3) << "thumb points medially";
    EXPECT_NEAR(std::abs(f.R_from_F.toRotationMatrix().determinant()), 1.0, 1e-12);
  }
}

// Where paper 1's protocol puts the forearm, relative to the body (the subject faces +z).
TEST(Exercises, ProtocolKeyPosesPutTheForearmWhereThePaperSays) {
  const BodyMotion m = make_exercise("forearm_protocol");
  const SkeletonPose head = pose_at(m, middle(phase(m, "behind_head")));
  EXPECT_LT(joint(head, body::kRightWrist).z(), joint(head, body::kHead).z() - 0.08) << "behind the head";
  // At head height: SMPL's head joint is the skull base, the template's head reaches 16 cm above.
  EXPECT_GT(joint(head, body::kRightWrist).y(), joint(head, body::kHead).y());
  EXPECT_LT(joint(head, body::kRightWrist).y(), joint(head, body::kHead).y() + 0.16);
  EXPECT_LT(std::abs(joint(head, body::kRightWrist).x()), 0.12) << "near the midline";
  const SkeletonPose belly = pose_at(m, middle(phase(m, "in_front_of_belly")));
  EXPECT_GT(joint(belly, body::kRightWrist).z(), joint(belly, body::kSpine1).z() + 0.12) << "in front";
  EXPECT_GT(joint(belly, body::kRightWrist).y(), joint(belly, body::kPelvis).y());
  EXPECT_LT(joint(belly, body::kRightWrist).y(), joint(belly, body::kSpine3).y());
  EXPECT_LT(std::abs(joint(belly, body::kRightWrist).x()), 0.08);
  const SkeletonPose back = pose_at(m, middle(phase(m, "behind_back")));
  EXPECT_LT(joint(back, body::kRightWrist).z(), joint(back, body::kSpine1).z() - 0.12) << "behind the back";
  EXPECT_GT(joint(back, body::kRightWrist).y(), joint(back, body::kPelvis).y() - 0.05);
  EXPECT_LT(joint(back, body::kRightWrist).y(), joint(back, body::kSpine3).y());
}

TEST(Exercises, OtherExercisesMoveTheRightParts) {
  const SkeletonPose rest = pose_at(make_exercise("arm_raising"), 0.0);
  // Shoulder lift: the collar lifts the shoulder joint by centimetres, the arm hangs.
  const BodyMotion lift = make_exercise("shoulder_lift");
  const SkeletonPose lifted = pose_at(lift, middle(phase(lift, "lifted")));
  EXPECT_GT(joint(lifted, body::kRightShoulder).y() - joint(rest, body::kRightShoulder).y(), 0.025);
  EXPECT_NEAR(joint(lifted, body::kLeftShoulder).y(), joint(rest, body::kLeftShoulder).y(), 1e-12);
  // Arm raising: the hand well above the head at the top.
  const BodyMotion raise = make_exercise("arm_raising");
  EXPECT_GT(joint(pose_at(raise, middle(phase(raise, "raised"))), body::kRightWrist).y(),
            joint(rest, body::kHead).y() + 0.2);
  // Torso tilt: the neck moves towards the side of the tilt, the pelvis stays.
  const BodyMotion tilt = make_exercise("torso_tilt");
  const SkeletonPose right = pose_at(tilt, middle(phase(tilt, "tilt_right")));
  const SkeletonPose left = pose_at(tilt, middle(phase(tilt, "tilt_left")));
  // 20 deg spread over spine1..3 moves the neck (0.4 m above spine1) sideways by about 10 cm.
  EXPECT_LT(joint(right, body::kNeck).x(), -0.06);
  EXPECT_GT(joint(left, body::kNeck).x(), 0.06);
  EXPECT_NEAR(joint(right, body::kNeck).x(), -joint(left, body::kNeck).x(), 1e-9);
  EXPECT_EQ(joint(right, body::kPelvis), joint(rest, body::kPelvis));
  // Air punching: the fist far in front at the punch, close at the guard.
  ExerciseOptions both;
  both.arm = ExerciseArm::kBoth;
  const BodyMotion punch = make_exercise("air_punching", both);
  EXPECT_GT(joint(pose_at(punch, phase(punch, "punch_right").end_s), body::kRightWrist).z(), 0.45);
  EXPECT_GT(joint(pose_at(punch, phase(punch, "punch_left").end_s), body::kLeftWrist).z(), 0.45);
  EXPECT_LT(joint(pose_at(punch, phase(punch, "punch_right").begin_s), body::kRightWrist).z(), 0.3);
  // Hair combing: the hand over the head throughout the combing strokes.
  const BodyMotion comb = make_exercise("hair_combing");
  const MotionPhase& strokes = phase(comb, "combing");
  for (double t = strokes.begin_s; t <= strokes.end_s; t += 0.05) {
    EXPECT_GT(joint(pose_at(comb, t), body::kRightWrist).y(), joint(rest, body::kHead).y()) << t;
  }
}

// Forearm rolling turns the forearm about its own axis (pronation/supination) while the elbow
// and wrist stay where they are.
TEST(Exercises, ForearmRollingTurnsTheForearmAboutItsAxis) {
  const BodyMotion m = make_exercise("forearm_rolling");
  const MotionPhase& rolling = phase(m, "rolling");
  const Quat rest_F = forearm_rest_R_from_F(rest_joints(), BodySide::kRight);
  const ForearmStrap strap;
  const ForearmPose start = forearm_pose(pose_at(m, rolling.begin_s), rest_F, strap);
  double largest_deg = 0.0;
  for (double t = rolling.begin_s; t <= rolling.end_s; t += 0.02) {
    const ForearmPose f = forearm_pose(pose_at(m, t), rest_F, strap);
    EXPECT_LT((f.elbow_R_m - start.elbow_R_m).norm(), 1e-9);
    EXPECT_LT((f.wrist_R_m - start.wrist_R_m).norm(), 1e-9);
    const Eigen::AngleAxisd turn(start.R_from_F.conjugate() * f.R_from_F);
    if (turn.angle() > 1e-6) {
      EXPECT_NEAR(std::abs(turn.axis().y()), 1.0, 1e-9) << t;
    }
    largest_deg = std::max(largest_deg, turn.angle() * 180 / pi);
  }
  EXPECT_NEAR(largest_deg, 60.0, 0.5);
  // The forearm points forwards (elbow at 90 deg), horizontal.
  const Vec3 fore = start.wrist_R_m - start.elbow_R_m;
  EXPECT_GT(fore.normalized().z(), 0.95);
}

// Speed scales the time line; repetitions add cycles.
TEST(Exercises, SpeedAndRepetitions) {
  ExerciseOptions slow, fast, more;
  slow.rest_hold_s = fast.rest_hold_s = more.rest_hold_s = 0.0;
  fast.speed = 2.0;
  more.repetitions = 6;
  const BodyMotion a = make_exercise("arm_raising", slow), b = make_exercise("arm_raising", fast),
                   c = make_exercise("arm_raising", more);
  EXPECT_NEAR(b.duration_s, a.duration_s / 2, 1e-9);
  EXPECT_NEAR(c.duration_s, 2 * a.duration_s, 1e-9);
  for (double t = 0; t <= b.duration_s; t += 0.1) EXPECT_LT((b.poses(t) - a.poses(2 * t)).norm(), 1e-9);
}

// A clip played behind the calibration pose (calibration_prefix.hpp): the calibration exercise up
// to the end of its hold, the clip shifted by hold end + blend afterwards, phases from both.
TEST(CalibrationPrefix, CalibrationHoldThenTheClipShifted) {
  ExerciseOptions both;
  both.arm = ExerciseArm::kBoth;
  const BodyMotion calibration = make_exercise("calibration_pose", both);
  const BodyMotion clip = make_exercise("arm_raising", both);
  const double blend_s = 1.5;
  const BodyMotion out = with_calibration_prefix(calibration, clip, blend_s);
  const double hold_end = calibration_hold_end_s(calibration);
  EXPECT_DOUBLE_EQ(calibration_hold_end_s(out), hold_end);
  EXPECT_NEAR(out.duration_s, hold_end + blend_s + clip.duration_s, 1e-12);
  for (const double t : {0.0, 1.0, hold_end}) EXPECT_LT((out.poses(t) - calibration.poses(t)).norm(), 1e-12) << t;
  for (const double t : {0.0, 1.0, clip.duration_s}) {
    EXPECT_LT((out.poses(hold_end + blend_s + t) - clip.poses(t)).norm(), 1e-12) << t;
  }
  // Inside the blend the pose lies between the two ends (the forearm between raised and hanging).
  const double mid_y = pose_at(out, hold_end + 0.5 * blend_s).joints.col(body::kRightWrist).y();
  const double held_y = pose_at(calibration, hold_end).joints.col(body::kRightWrist).y();
  const double clip_y = pose_at(clip, 0.0).joints.col(body::kRightWrist).y();
  EXPECT_LT(mid_y, std::max(held_y, clip_y));
  EXPECT_GT(mid_y, std::min(held_y, clip_y));
  EXPECT_NEAR(phase(out, "raised").begin_s, phase(clip, "raised").begin_s + hold_end + blend_s, 1e-12);
  EXPECT_THROW(calibration_hold_end_s(clip), Error);
}

// The calibration pose after a clip (calibration_prefix.hpp): the clip up to its last blend, the
// whole calibration exercise shifted by the clip's duration, phases from both.
TEST(CalibrationSuffix, TheClipThenTheCalibrationExerciseShifted) {
  ExerciseOptions both;
  both.arm = ExerciseArm::kBoth;
  const BodyMotion calibration = make_exercise("calibration_pose", both);
  const BodyMotion clip = make_exercise("arm_raising", both);
  const double blend_s = 1.5;
  const BodyMotion out = with_calibration_suffix(clip, calibration, blend_s);
  EXPECT_NEAR(out.duration_s, clip.duration_s + calibration.duration_s, 1e-12);
  for (const double t : {0.0, 1.0, clip.duration_s - blend_s}) {
    EXPECT_LT((out.poses(t) - clip.poses(t)).norm(), 1e-12) << t;
  }
  for (const double t : {0.0, 1.0, calibration_hold_end_s(calibration), calibration.duration_s}) {
    EXPECT_LT((out.poses(clip.duration_s + t) - calibration.poses(t)).norm(), 1e-12) << t;
  }
  // Inside the blend the pose lies between the clip's and the calibration's start.
  const double t_mid = clip.duration_s - 0.5 * blend_s;
  const double mid_y = pose_at(out, t_mid).joints.col(body::kRightWrist).y();
  const double clip_y = pose_at(clip, t_mid).joints.col(body::kRightWrist).y();
  const double rest_y = pose_at(calibration, 0.0).joints.col(body::kRightWrist).y();
  EXPECT_LE(mid_y, std::max(clip_y, rest_y) + 1e-9);
  EXPECT_GE(mid_y, std::min(clip_y, rest_y) - 1e-9);
  EXPECT_NEAR(calibration_hold_end_s(out), clip.duration_s + calibration_hold_end_s(calibration), 1e-12);
  EXPECT_NEAR(phase(out, "raised").begin_s, phase(clip, "raised").begin_s, 1e-12);
  // A clip shorter than the blend is refused by name.
  BodyMotion short_clip = clip;
  short_clip.duration_s = 1.0;
  EXPECT_THROW(with_calibration_suffix(short_clip, calibration, blend_s), Error);
}
