#include "sim/motion_library.hpp"

#include <cmath>

#include "common/error.hpp"
#include "sim/option_checks.hpp"

namespace posefuse::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The scripted right-arm chain (scripted_motion.hpp) set up on the body's right arm; the left
// arm is its mirror image across the subject's sagittal plane, with F's z flipped so that F
// stays right-handed (z to the little finger on the left arm).
std::array<std::function<ForearmPose(double)>, 2> chain_forearms(
    const MotionContext& context, const std::array<std::function<ArmAngles(double)>, 2>& angles) {
  const Eigen::Matrix3d W_from_S = Eigen::AngleAxisd(context.heading_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Matrix3d mirror_W = W_from_S * Eigen::Vector3d(1, -1, 1).asDiagonal() * W_from_S.transpose();
  const Eigen::Matrix3d flip_z = Eigen::Vector3d(1, 1, -1).asDiagonal();
  std::array<std::function<ForearmPose(double)>, 2> out;
  for (int arm = 0; arm < 2; ++arm) {
    const int shoulder = arm == 0 ? body::kLeftShoulder : body::kRightShoulder;
    const int elbow = arm == 0 ? body::kLeftElbow : body::kRightElbow;
    ArmGeometry geometry;
    const Vec3 shoulder_W = context.W_from_Body * context.rest_joints.col(shoulder);
    geometry.shoulder_p_W_m = arm == 0 ? Vec3(mirror_W * shoulder_W) : shoulder_W;
    geometry.heading_rad = context.heading_rad;
    geometry.upper_arm_m = (context.rest_joints.col(elbow) - context.rest_joints.col(shoulder)).norm();
    geometry.strap_to_elbow_m = context.strap_to_elbow_m;
    const auto arm_angles = angles[static_cast<std::size_t>(arm)];
    out[static_cast<std::size_t>(arm)] = [=](double t_s) {
      const ArmPose pose = arm_pose(geometry, arm_angles(t_s));
      ForearmPose f;
      f.W_from_F = pose.W_from_F.toRotationMatrix();
      f.strap_p_W_m = pose.strap_p_W_m;
      if (arm == 0) {
        f.W_from_F = mirror_W * f.W_from_F * flip_z;
        f.strap_p_W_m = mirror_W * f.strap_p_W_m;
      }
      return f;
    };
  }
  return out;
}

// arm_raising_sequence (camera_session.hpp) turns each arm about the body's forward axis from
// -75 deg (below the T-pose) to +75 deg and back. In the arm chain that is abduction from
// 15 deg (hanging is 0) to 165 deg, in the same plane.
SimMotion arm_raising_motion(const MotionOptions& options, const MotionContext& context) {
  SimMotion motion;
  motion.layout = body::PoseLayout::full_body();
  motion.poses = arm_raising_sequence(motion.layout, options.period_s);
  const double period = options.period_s;
  const auto angles = [period](double t_s) {
    const double raise = 0.5 * (1.0 - std::cos(2 * kPi * t_s / period));
    ArmAngles a;
    a.shoulder_abduction_rad = kPi / 2 + (-75.0 + 150.0 * raise) * kPi / 180.0;
    return a;
  };
  motion.forearm = chain_forearms(context, {angles, angles});
  return motion;
}

}  // namespace

std::vector<std::string> motion_names() { return {"arm_raising"}; }

SimMotion select_motion(const std::string& name, const MotionOptions& options, const MotionContext& context) {
  require_positive(options.period_s, "motion_period_s");
  if (context.rest_joints.cols() != body::kNumJoints || !context.rest_joints.allFinite()) {
    throw_invalid("context.rest_joints", "must be 3 x 24 finite values");
  }
  if (name == "arm_raising") return arm_raising_motion(options, context);
  std::string known;
  for (const auto& n : motion_names()) known += (known.empty() ? "" : ", ") + n;
  throw_invalid("motion", "'" + name + "' is not a known motion (known: " + known + ")");
}

}  // namespace posefuse::sim
