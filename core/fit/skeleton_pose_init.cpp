#include "fit/skeleton_pose_init.hpp"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include "common/error.hpp"
#include "body/body_evaluator.hpp"
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
    fallbacks.push_back({segment, why + (has_previous ? "; kept the previous pose" : "; left at the rest pose (no previous pose)")});
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
  }

  bool has_dofs(int joint) const { return !layout.dofs_of_joint(joint).empty(); }

  void global() {
    const std::string why = unusable({kSpineBase, kSpineMid, kHipLeft, kHipRight});
    if (!why.empty()) {
      if (!has_previous) {
        const int joint = [&] {
          for (int j : {kSpineBase, kSpineMid, kHipLeft, kHipRight})
            if (!joint_unusable_reason(skeleton, j, options.accept_inferred_joints).empty()) return j;
          return int(kSpineBase);
        }();
        throw_precondition(std::string("skeleton.") + kinect_joint_name(joint),
                           why + ": the global pose needs SpineBase, SpineMid, HipLeft and HipRight when there is no previous pose");
      }
      fall_back(InitSegment::kGlobal, why);
      return;
    }
    const Eigen::Vector3d hips = obs(kHipLeft) - obs(kHipRight), spine = obs(kSpineMid) - obs(kSpineBase);
    if (!long_enough(InitSegment::kGlobal, hips, kHipRight, kHipLeft) ||
        !long_enough(InitSegment::kGlobal, spine, kSpineBase, kSpineMid)) {
      if (!has_previous) throw_precondition("skeleton", "the global pose cannot be built: " + fallbacks.back().reason);
      return;
    }
    const Eigen::Matrix3d r = best_rotation(rest.col(body::kLeftHip) - rest.col(body::kRightHip),
                                            rest.col(body::kSpine2) - rest.col(body::kPelvis), hips, spine);
    set_joint_rotation(body::kPelvis, nearest_equivalent(rotation_vector(r), joint_rotation_vector(body::kPelvis)));
    const Eigen::Vector3d translation = obs(kSpineBase) - rest.col(body::kPelvis);
    for (int d : layout.dofs_of_joint(body::kPelvis))
      if (layout.dof(d).kind == body::DofKind::kTranslation) theta[d] = translation.dot(layout.dof(d).axis);
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

  void collar(InitSegment segment, int collar, int shoulder, int observed_shoulder) {
    if (!has_dofs(collar)) return;
    const std::string why = unusable({observed_shoulder});
    if (!why.empty()) return fall_back(segment, why);
    const JointPose pose = pose_joints(rest, layout, theta);
    const Eigen::Vector3d bone = obs(observed_shoulder) - pose.positions_K.col(collar);
    if (bone.norm() < options.min_bone_length_m)
      return fall_back(segment, std::string(kinect_joint_name(observed_shoulder)) + " lies on the model's collar joint");
    swing(collar, rest.col(shoulder) - rest.col(collar), bone);
  }

  void limb(InitSegment segment, int joint, int child, int observed_from, int observed_to) {
    if (!has_dofs(joint)) return;
    const std::string why = unusable({observed_from, observed_to});
    if (!why.empty()) return fall_back(segment, why);
    const Eigen::Vector3d bone = obs(observed_to) - obs(observed_from);
    if (!long_enough(segment, bone, observed_from, observed_to)) return;
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
  return std::any_of(fallbacks.begin(), fallbacks.end(), [&](const SegmentFallback& f) { return f.segment == segment; });
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
    throw_invalid("init_options.min_bone_length_m", "must be positive, got " + std::to_string(options_.min_bone_length_m));
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

  Builder b{layout_, rest_joints_, options_, skeleton, has_previous, has_previous ? previous_theta : layout_.zero(), {}};
  b.global();
  b.spine();
  b.neck();
  b.collar(InitSegment::kLeftCollar, body::kLeftCollar, body::kLeftShoulder, kShoulderLeft);
  b.collar(InitSegment::kRightCollar, body::kRightCollar, body::kRightShoulder, kShoulderRight);
  b.limb(InitSegment::kLeftShoulder, body::kLeftShoulder, body::kLeftElbow, kShoulderLeft, kElbowLeft);
  b.limb(InitSegment::kRightShoulder, body::kRightShoulder, body::kRightElbow, kShoulderRight, kElbowRight);
  b.limb(InitSegment::kLeftElbow, body::kLeftElbow, body::kLeftWrist, kElbowLeft, kWristLeft);
  b.limb(InitSegment::kRightElbow, body::kRightElbow, body::kRightWrist, kElbowRight, kWristRight);
  b.limb(InitSegment::kLeftWrist, body::kLeftWrist, body::kLeftHand, kWristLeft, kHandLeft);
  b.limb(InitSegment::kRightWrist, body::kRightWrist, body::kRightHand, kWristRight, kHandRight);
  b.limb(InitSegment::kLeftHip, body::kLeftHip, body::kLeftKnee, kHipLeft, kKneeLeft);
  b.limb(InitSegment::kRightHip, body::kRightHip, body::kRightKnee, kHipRight, kKneeRight);
  b.limb(InitSegment::kLeftKnee, body::kLeftKnee, body::kLeftAnkle, kKneeLeft, kAnkleLeft);
  b.limb(InitSegment::kRightKnee, body::kRightKnee, body::kRightAnkle, kKneeRight, kAnkleRight);

  SkeletonInitResult result;
  result.theta = std::move(b.theta);
  result.fallbacks = std::move(b.fallbacks);
  if (options_.clamp_to_limits)
    for (int d = 0; d < layout_.size(); ++d) {
      const body::Dof& dof = layout_.dof(d);
      if (!dof.limited) continue;
      const double clamped = std::clamp(result.theta[d], dof.min_rad, dof.max_rad);
      if (clamped != result.theta[d]) result.clamped_dofs.push_back(d);
      result.theta[d] = clamped;
    }
  return result;
}

}  // namespace posefuse::fit
