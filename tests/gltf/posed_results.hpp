#pragma once
// A result directory of known SMPL poses, written through session::ResultFiles as the client
// writes a fitted session: the joints and global rotations of BodyEvaluator (the model's own
// skinning) for the female template with a personalised shape, and a level camera.
#include <filesystem>
#include <memory>
#include <vector>

#include "body/body_evaluator.hpp"
#include "body/template_generator.hpp"
#include "geometry/quaternion.hpp"
#include "session/result_files.hpp"
#include "session/stages/proto_values.hpp"

namespace posefuse::gltf_fixture {

struct Pose {
  Eigen::Matrix3Xd rotation_vectors = Eigen::Matrix3Xd::Zero(3, body::kNumJoints);  // SMPL's, local
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
};

inline Eigen::VectorXd fixture_beta() {
  Eigen::VectorXd beta = Eigen::VectorXd::Zero(10);
  beta << 0.5, -0.3, 0.2, 0.0, 0.4, -0.2, 0.1, 0.3, -0.1, 0.2;
  return beta;
}

// Upright, facing a level camera (K: Kinect's camera space, y up, z away from the camera) 2.5 m
// away: SMPL's front (+z) onto -z_K. Frame f moves the arms, the spine and the root a little.
inline Pose fixture_pose(int f) {
  Pose pose;
  pose.rotation_vectors.col(body::kPelvis) = Eigen::Vector3d(0.05 * f, M_PI - 0.1 * f, 0.02);
  pose.translation = Eigen::Vector3d(0.1 - 0.02 * f, -0.3, 2.5 + 0.01 * f);
  pose.rotation_vectors.col(body::kSpine1) = Eigen::Vector3d(0.1, 0.05 * f, 0.0);
  pose.rotation_vectors.col(body::kLeftShoulder) = Eigen::Vector3d(0.0, 0.2, -0.3 - 0.1 * f);
  pose.rotation_vectors.col(body::kLeftElbow) = Eigen::Vector3d(0.0, -0.3 * f, 0.0);
  pose.rotation_vectors.col(body::kRightShoulder) = Eigen::Vector3d(0.2 * f, 0.0, 0.4);
  pose.rotation_vectors.col(body::kRightElbow) = Eigen::Vector3d(0.0, 1.2, 0.0);
  pose.rotation_vectors.col(body::kLeftHip) = Eigen::Vector3d(-0.2 * f, 0.0, 0.0);
  pose.rotation_vectors.col(body::kHead) = Eigen::Vector3d(0.0, 0.3, 0.1 * f);
  return pose;
}

// Poses `evaluator` (the all_joints layout) as `pose`.
inline void evaluate(body::BodyEvaluator& evaluator, const Eigen::VectorXd& beta, const Pose& pose) {
  const body::PoseLayout& layout = evaluator.layout();
  Eigen::VectorXd theta = layout.zero();
  for (int d = 0; d < layout.size(); ++d) {
    const body::Dof& dof = layout.dof(d);
    theta[d] =
        dof.axis.dot(dof.kind == body::DofKind::kTranslation ? pose.translation
                                                             : Eigen::Vector3d(pose.rotation_vectors.col(dof.joint)));
  }
  evaluator.evaluate(beta, theta, body::Derivatives::kNone);
}

inline std::shared_ptr<const body::SmplModel> fixture_model() { return body::make_template(body::Sex::kFemale); }

struct PosedResultsSpec {
  std::int64_t t0_us = 1'000'000;
  bool with_rotations = true;    // false: the body fit was off
  bool with_shape = true;        // false: a calibration report without betas and body model
  bool flip_odd_frames = false;  // odd frames' rotations written as -q (the same rotations)
};

// One fitted frame per pose, 30 Hz from spec.t0_us.
inline void write_posed_results(const std::filesystem::path& dir, const std::vector<Pose>& poses,
                                const PosedResultsSpec& spec = {}) {
  using session::to_proto;
  body::BodyEvaluator evaluator(fixture_model(), body::PoseLayout::all_joints());
  session::ResultFiles files(dir);
  for (size_t f = 0; f < poses.size(); ++f) {
    evaluate(evaluator, fixture_beta(), poses[f]);
    v1::FrameResult frame;
    frame.set_t_us(spec.t0_us + static_cast<std::int64_t>(f) * 33'333);
    for (int j = 0; j < body::kNumJoints; ++j) {
      v1::JointEstimate& joint = *frame.add_smpl_joints();
      *joint.mutable_position_m() = to_proto(Eigen::Vector3d(evaluator.joints().col(j)));
      joint.set_source(v1::VISUAL);
      joint.set_confidence(1.0);
      if (spec.with_rotations)
        *frame.add_smpl_joint_rotations() = to_proto(geometry::Quat(
            (spec.flip_odd_frames && f % 2 == 1 ? -1.0 : 1.0) * geometry::Quat(evaluator.joint_rotation(j)).coeffs()));
    }
    files.write_frame(frame);
  }
  v1::CalibrationReport report;
  if (spec.with_shape) {
    const Eigen::VectorXd beta = fixture_beta();
    for (int b = 0; b < beta.size(); ++b) report.mutable_body_shape()->add_betas(beta[b]);
    report.mutable_body_shape()->set_estimated(true);
    report.mutable_body_shape()->set_body_model(v1::BodyShape::TEMPLATE_FEMALE);
  }
  // A level camera: the world's z (up) is K's y.
  *report.mutable_k_from_w() = to_proto(geometry::quat_from_rotation_vector(geometry::Vec3(-M_PI / 2, 0, 0)));
  files.write_calibration(report);
  files.close();
}

}  // namespace posefuse::gltf_fixture
