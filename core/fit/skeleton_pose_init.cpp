#include "fit/skeleton_pose_init.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include "body/body_evaluator.hpp"
#include "common/error.hpp"
#include "fit/joint_kinematics.hpp"

namespace posefuse::fit {

using body::Joint;

namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

// Rotation R that best maps the rest vectors a onto the observed vectors b (Kabsch on the two
// unit vectors and their normalised cross product, equally weighted).
Eigen::Matrix3d best_rotation(const Eigen::Vector3d& a1, const Eigen::Vector3d& a2, const Eigen::Vector3d& b1,
                              const Eigen::Vector3d& b2) {
  const Eigen::Vector3d a[3] = {a1.normalized(), a2.normalized(), a1.cross(a2).normalized()};
  const Eigen::Vector3d b[3] = {b1.normalized(), b2.normalized(), b1.cross(b2).normalized()};
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (int i = 0; i < 3; ++i) h += a[i] * b[i].transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixV() * d * svd.matrixU().transpose();
}

Eigen::Vector3d rotation_vector(const Eigen::Matrix3d& r) {
  const Eigen::AngleAxisd aa(r);
  return aa.angle() * aa.axis();
}

// Of the rotation vectors w and (|w| - 2 pi) w / |w| (the same rotation), the one nearer
// `reference`: keeps the pelvis representation continuous across frames near 180 degrees, which
// the moving average over theta needs.
Eigen::Vector3d nearest_equivalent(const Eigen::Vector3d& w, const Eigen::Vector3d& reference) {
  const double angle = w.norm();
  if (angle < 1e-9) return w;
  const Eigen::Vector3d other = w * ((angle - kTwoPi) / angle);
  return (other - reference).squaredNorm() < (w - reference).squaredNorm() ? other : w;
}

struct Builder {
  const body::PoseLayout& layout;
  const Eigen::Matrix3Xd& rest;
  const SkeletonInitOptions& options;
  const TrackedSkeleton& skeleton;
  const bool has_previous;
  Eigen::VectorXd theta;
  std::vector<SegmentFallback> fallbacks;
  std::vector<int> clamped_dofs;

  // Clamps a joint's limited DOFs as soon as they are built, so that its children are aimed from
  // the pose the joint will really have.
  void clamp(int joint) {
    if (!options.clamp_to_limits) return;
    for (int d : layout.dofs_of_joint(joint)) {
      const body::Dof& dof = layout.dof(d);
      if (!dof.limited) continue;
      const double clamped = std::clamp(theta[d], dof.min_rad, dof.max_rad);
      if (clamped != theta[d]) clamped_dofs.push_back(d);
      theta[d] = clamped;
    }
  }

  Eigen::Vector3d obs(int joint) const { return skeleton.positions_K[joint]; }

  // "" when every joint is usable, else the first reason.
  std::string unusable(std::initializer_list<int> joints) const {
    for (int j : joints) {
      std::string reason = joint_unusable_reason(skeleton, j, options.accept_inferred_joints);
      if (!reason.empty()) return reason;
    }
    return "";
  }

  void fall_back(InitSegment segment, const std::string& why) {
    fallbacks.push_back(
        {segment, why + (has_previous ? "; kept the previous pose" : "; left at the rest pose (no previous pose)")});
  }

  bool long_enough(InitSegment segment, const Eigen::Vector3d& v, int from, int to) {
    if (v.norm() >= options.min_bone_length_m) return true;
    fall_back(segment, std::string(kinect_joint_name(from)) + " and " + kinect_joint_name(to) + " are " +
                           std::to_string(v.norm()) + " m apart");
    return false;
  }

  void set_joint_rotation(int joint, const Eigen::Vector3d& w) {
    for (int d : layout.dofs_of_joint(joint))
      if (layout.dof(d).kind == body::DofKind::kRotation) theta[d] = w.dot(layout.dof(d).axis);
  }

  Eigen::Vector3d joint_rotation_vector(int joint) const {
    Eigen::Vector3d w = Eigen::Vector3d::Zero();
    for (int d : layout.dofs_of_joint(joint))
      if (layout.dof(d).kind == body::DofKind::kRotation) w += theta[d] * layout.dof(d).axis;
    return w;
  }

  // Smallest rotation of `joint` taking its rest bone `rest_bone` (canonical frame) onto the
  // observed direction `bone_K`, projected onto the joint's DOF axes.
  void swing(int joint, const Eigen::Vector3d& rest_bone, const Eigen::Vector3d& bone_K) {
    const JointPose pose = pose_joints(rest, layout, theta);
    const int parent = body::kSmplParents[joint];
    const Eigen::Vector3d target = (pose.K_from_joint[parent].transpose() * bone_K).normalized();
    const Eigen::Vector3d from = rest_bone.normalized();
    const Eigen::Vector3d cross = from.cross(target);
    const double angle = std::atan2(cross.norm(), from.dot(target));
    Eigen::Vector3d axis;
    if (cross.norm() > 1e-12) {
      axis = cross.normalized();
    } else {
      // Parallel (nothing to do) or opposite: any axis perpendicular to the bone; take the first
      // DOF axis that is.
      axis = from.unitOrthogonal();
      for (int d : layout.dofs_of_joint(joint))
        if (std::abs(layout.dof(d).axis.dot(from)) < 1e-6) {
          axis = layout.dof(d).axis;
          break;
        }
    }
    set_joint_rotation(joint, angle * axis);
    clamp(joint);
  }

  bool has_dofs(int joint) const { return !layout.dofs_of_joint(joint).empty(); }

  // Rigid fit of the model's straight rest trunk to the observed trunk joints (Kabsch with
  // translation): the long shoulder and spine baselines keep the pelvis rotation from inheriting
  // the few-centimetre errors of the hip joints, which only 17 cm apart would turn it by 10-20 deg.
  void global() {
    const Eigen::Vector3d rest_collars = 0.5 * (rest.col(body::kLeftCollar) + rest.col(body::kRightCollar));
    const std::pair<int, Eigen::Vector3d> trunk[] = {{kSpineBase, rest.col(body::kPelvis)},
                                                     {kSpineMid, rest.col(body::kSpine2)},
                                                     {kHipLeft, rest.col(body::kLeftHip)},
                                                     {kHipRight, rest.col(body::kRightHip)},
                                                     {kSpineShoulder, rest_collars},
                                                     {kShoulderLeft, rest.col(body::kLeftShoulder)},
                                                     {kShoulderRight, rest.col(body::kRightShoulder)}};
    std::vector<Eigen::Vector3d> from, to;
    std::string first_missing;
    int first_missing_joint = kSpineBase;
    for (const auto& [joint, rest_point] : trunk) {
      const std::string why = joint_unusable_reason(skeleton, joint, options.accept_inferred_joints);
      if (why.empty()) {
        from.push_back(rest_point);
        to.push_back(obs(joint));
      } else if (first_missing.empty()) {
        first_missing = why;
        first_missing_joint = joint;
      }
    }
    Eigen::Vector3d from_mean = Eigen::Vector3d::Zero(), to_mean = Eigen::Vector3d::Zero();
    for (size_t i = 0; i < from.size(); ++i) {
      from_mean += from[i] / static_cast<double>(from.size());
      to_mean += to[i] / static_cast<double>(from.size());
    }
    Eigen::Matrix3d h = Eigen::Matrix3d::Zero(), spread = Eigen::Matrix3d::Zero();
    for (size_t i = 0; i < from.size(); ++i) {
      h += (from[i] - from_mean) * (to[i] - to_mean).transpose();
      spread += (to[i] - to_mean) * (to[i] - to_mean).transpose();
    }
    // Needs three joints that do not lie on one line.
    const Eigen::Vector3d extent = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(spread).eigenvalues();
    if (from.size() < 3 || extent[1] < options.min_bone_length_m * options.min_bone_length_m) {
      const std::string why = std::to_string(from.size()) + " of the 7 trunk joints usable" +
                              (first_missing.empty() ? std::string(", all on one line") : " (" + first_missing + ")");
      if (!has_previous)
        throw_precondition(std::string("skeleton.") + kinect_joint_name(first_missing_joint),
                           why +
                               ": the global pose needs three trunk joints (SpineBase, SpineMid, SpineShoulder, "
                               "hips, shoulders) when there is no previous pose");
      return fall_back(InitSegment::kGlobal, why);
    }
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
    d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
    const Eigen::Matrix3d r = svd.matrixV() * d * svd.matrixU().transpose();
    set_joint_rotation(body::kPelvis, nearest_equivalent(rotation_vector(r), joint_rotation_vector(body::kPelvis)));
    // The pelvis joint's posed position is J(0) + translation.
    const Eigen::Vector3d translation = to_mean + r * (rest.col(body::kPelvis) - from_mean) - rest.col(body::kPelvis);
    for (int dof : layout.dofs_of_joint(body::kPelvis))
      if (layout.dof(dof).kind == body::DofKind::kTranslation) theta[dof] = translation.dot(layout.dof(dof).axis);
  }

  void spine() {
    const std::string why = unusable({kSpineMid, kSpineShoulder, kShoulderLeft, kShoulderRight});
    if (!why.empty()) return fall_back(InitSegment::kSpine, why);
    const Eigen::Vector3d shoulders = obs(kShoulderLeft) - obs(kShoulderRight);
    const Eigen::Vector3d upper = obs(kSpineShoulder) - obs(kSpineMid);
    if (!long_enough(InitSegment::kSpine, shoulders, kShoulderRight, kShoulderLeft) ||
        !long_enough(InitSegment::kSpine, upper, kSpineMid, kSpineShoulder))
      return;
    const Eigen::Vector3d rest_collars = 0.5 * (rest.col(body::kLeftCollar) + rest.col(body::kRightCollar));
    const Eigen::Matrix3d upper_K = best_rotation(rest.col(body::kLeftShoulder) - rest.col(body::kRightShoulder),
                                                  rest_collars - rest.col(body::kSpine2), shoulders, upper);
    set_joint_rotation(body::kSpine1, Eigen::Vector3d::Zero());
    const JointPose pose = pose_joints(rest, layout, theta);
    const Eigen::Vector3d w = rotation_vector(pose.K_from_joint[body::kSpine1].transpose() * upper_K);
    set_joint_rotation(body::kSpine2, 0.5 * w);
    set_joint_rotation(body::kSpine3, 0.5 * w);
    clamp(body::kSpine2);
    clamp(body::kSpine3);
  }

  void neck() {
    if (!has_dofs(body::kNeck)) return;
    const std::string why = unusable({kNeck, kHead});
    if (!why.empty()) return fall_back(InitSegment::kNeck, why);
    const Eigen::Vector3d bone = obs(kHead) - obs(kNeck);
    if (!long_enough(InitSegment::kNeck, bone, kNeck, kHead)) return;
    const Eigen::Vector3d head_up = body::rotation_from_vector(joint_rotation_vector(body::kHead)).col(1);
    swing(body::kNeck, rest.col(body::kHead) - rest.col(body::kNeck) + options.head_above_skull_base_m * head_up, bone);
  }

  // Aims the bone from the model's posed joint at the observed child joint (rather than along the
  // observed bone): each built joint then inherits the error of one observed joint instead of
  // the sum of the errors along the chain.
  void limb(InitSegment segment, int joint, int child, int observed_child) {
    if (!has_dofs(joint)) return;
    const std::string why = unusable({observed_child});
    if (!why.empty()) return fall_back(segment, why);
    const JointPose pose = pose_joints(rest, layout, theta);
    const Eigen::Vector3d bone = obs(observed_child) - pose.positions_K.col(joint);
    if (bone.norm() < options.min_bone_length_m)
      return fall_back(segment, std::string(kinect_joint_name(observed_child)) + " lies on the model's " +
                                    body::smpl_joint_names()[joint] + " joint");
    swing(joint, rest.col(child) - rest.col(joint), bone);
  }
};

}  // namespace

const char* init_segment_name(InitSegment segment) {
  switch (segment) {
    case InitSegment::kGlobal: return "global";
    case InitSegment::kSpine: return "spine";
    case InitSegment::kNeck: return "neck";
    case InitSegment::kLeftCollar: return "left_collar";
    case InitSegment::kRightCollar: return "right_collar";
    case InitSegment::kLeftShoulder: return "left_shoulder";
    case InitSegment::kRightShoulder: return "right_shoulder";
    case InitSegment::kLeftElbow: return "left_elbow";
    case InitSegment::kRightElbow: return "right_elbow";
    case InitSegment::kLeftWrist: return "left_wrist";
    case InitSegment::kRightWrist: return "right_wrist";
    case InitSegment::kLeftHip: return "left_hip";
    case InitSegment::kRightHip: return "right_hip";
    case InitSegment::kLeftKnee: return "left_knee";
    case InitSegment::kRightKnee: return "right_knee";
  }
  return "?";
}

bool SkeletonInitResult::fell_back(InitSegment segment) const {
  return std::any_of(fallbacks.begin(), fallbacks.end(),
                     [&](const SegmentFallback& f) { return f.segment == segment; });
}

SkeletonPoseInitializer::SkeletonPoseInitializer(std::shared_ptr<const body::SmplModel> model, body::PoseLayout layout,
                                                 const Eigen::VectorXd& beta, const SkeletonInitOptions& options)
    : model_(std::move(model)), layout_(std::move(layout)), options_(options) {
  if (!model_) throw_invalid("model", "is null");
  body::validate(*model_);
  if (!std::isfinite(options_.head_above_skull_base_m) || std::abs(options_.head_above_skull_base_m) > 0.5)
    throw_invalid("init_options.head_above_skull_base_m",
                  "must be finite and within 0.5 m, got " + std::to_string(options_.head_above_skull_base_m));
  if (!std::isfinite(options_.min_bone_length_m) || options_.min_bone_length_m <= 0)
    throw_invalid("init_options.min_bone_length_m",
                  "must be positive, got " + std::to_string(options_.min_bone_length_m));
  rest_joints_ = fit::rest_joints(*model_, beta);
}

SkeletonInitResult SkeletonPoseInitializer::initialise(const TrackedSkeleton& skeleton,
                                                       const Eigen::VectorXd& previous_theta) const {
  const bool has_previous = previous_theta.size() > 0;
  if (has_previous) {
    if (previous_theta.size() != layout_.size())
      throw_invalid("previous_theta", "size " + std::to_string(previous_theta.size()) + ", layout has " +
                                          std::to_string(layout_.size()) + " DOF");
    if (!previous_theta.allFinite()) throw_invalid("previous_theta", "not finite");
  }
  bool any_usable = false;
  for (int j = 0; j < kKinectJointCount; ++j)
    any_usable = any_usable || joint_unusable_reason(skeleton, j, options_.accept_inferred_joints).empty();
  if (!any_usable)
    throw_precondition("skeleton", options_.accept_inferred_joints
                                       ? "no joint is tracked or inferred with a finite position"
                                       : "no joint is tracked with a finite position");

  Builder b{layout_, rest_joints_, options_, skeleton, has_previous, has_previous ? previous_theta : layout_.zero(), {},
            {}};
  b.global();
  b.spine();
  b.neck();
  // Root first: each segment is aimed from its parent's pose as built so far.
  struct Limb {
    InitSegment segment;
    int joint, child, observed_child;
  };
  static constexpr Limb kLimbs[] = {
      {InitSegment::kLeftCollar, body::kLeftCollar, body::kLeftShoulder, kShoulderLeft},
      {InitSegment::kRightCollar, body::kRightCollar, body::kRightShoulder, kShoulderRight},
      {InitSegment::kLeftShoulder, body::kLeftShoulder, body::kLeftElbow, kElbowLeft},
      {InitSegment::kRightShoulder, body::kRightShoulder, body::kRightElbow, kElbowRight},
      {InitSegment::kLeftElbow, body::kLeftElbow, body::kLeftWrist, kWristLeft},
      {InitSegment::kRightElbow, body::kRightElbow, body::kRightWrist, kWristRight},
      {InitSegment::kLeftWrist, body::kLeftWrist, body::kLeftHand, kHandLeft},
      {InitSegment::kRightWrist, body::kRightWrist, body::kRightHand, kHandRight},
      {InitSegment::kLeftHip, body::kLeftHip, body::kLeftKnee, kKneeLeft},
      {InitSegment::kRightHip, body::kRightHip, body::kRightKnee, kKneeRight},
      {InitSegment::kLeftKnee, body::kLeftKnee, body::kLeftAnkle, kAnkleLeft},
      {InitSegment::kRightKnee, body::kRightKnee, body::kRightAnkle, kAnkleRight},
  };
  for (const Limb& l : kLimbs) b.limb(l.segment, l.joint, l.child, l.observed_child);

  SkeletonInitResult result;
  // DOFs kept from the previous pose are clamped too.
  for (int joint = 0; joint < body::kNumJoints; ++joint) b.clamp(joint);
  std::sort(b.clamped_dofs.begin(), b.clamped_dofs.end());
  b.clamped_dofs.erase(std::unique(b.clamped_dofs.begin(), b.clamped_dofs.end()), b.clamped_dofs.end());
  result.theta = std::move(b.theta);
  result.fallbacks = std::move(b.fallbacks);
  result.clamped_dofs = std::move(b.clamped_dofs);
  return result;
}

}  // namespace posefuse::fit
