#include "sim/angle_truth.hpp"

#include "body/smpl_model.hpp"
#include "fit/arm_roll.hpp"

namespace posefuse::sim {

AngleTruth angle_truth(const SimTruth& truth, const measures::JointAngleOptions& angle_options,
                       const measures::RepetitionOptions& repetition_options) {
  AngleTruth out;
  measures::AngleSeries series;
  const Vec3 up_K = truth.K_from_W * Vec3::UnitZ();  // W is z up
  const measures::JointAngles* previous = nullptr;
  // The truth's joints and arm segments are the subject's own: its angles are exact (confidence
  // 1) except where the geometry defines none (confidence 0: the gimbal lock's held values).
  const measures::JointAngleOptions exact_joints = measures::exact_joint_options(angle_options);
  out.frames.reserve(truth.frames.size());
  for (const SimFrameTruth& frame : truth.frames) {
    measures::PosedUpperBody body;
    body.smpl_joints_K = frame.smpl_joints_K;
    body.joint_confidence.fill(1.0);
    body.up_K = up_K;
    for (const SimArmTruth& arm : truth.arms) {
      if (!arm.has_imu) continue;  // the server has no pronation without the wrist IMU either
      const bool left = arm.arm == 0;
      const auto& J = frame.smpl_joints_K;
      const Vec3 thumb_K = frame.K_from_F[static_cast<std::size_t>(arm.arm)] *
                           fit::thumb_axis_F(left ? fit::ArmSide::kLeft : fit::ArmSide::kRight);
      const auto rad = measures::pronation_rad(
          J.col(left ? body::kLeftShoulder : body::kRightShoulder), J.col(left ? body::kLeftElbow : body::kRightElbow),
          J.col(left ? body::kLeftWrist : body::kRightWrist), thumb_K, left, angle_options.min_elbow_flexion_deg);
      if (rad) (left ? body.left_pronation : body.right_pronation) = measures::PronationInput{*rad, 1.0};
    }
    out.frames.push_back(measures::joint_angles(body, exact_joints, previous));
    previous = &out.frames.back();
    series.add(static_cast<double>(frame.t_us) * 1e-6, out.frames.back());
  }
  out.repetitions = series.repetitions(repetition_options);
  return out;
}

}  // namespace posefuse::sim
