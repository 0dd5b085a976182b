#include "sim/camera_skeleton.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "common/error.hpp"
#include "fit/camera_joints.hpp"
#include "sim/option_checks.hpp"
#include "sim/sim_rng.hpp"

namespace posefuse::sim {

using enum geometry::KinectJoint;

namespace {

using body::Joint;
using std::numbers::pi;
constexpr int kNone = -1;

// SMPL joint whose rotation carries the bone parent -> camera joint (kNone: end joints,
// which report no orientation). SpineBase reports the pelvis rotation itself.
constexpr std::array<int, kCameraJointCount> kSmplRotatingBone = {body::kPelvis,
                                                                  body::kSpine1,
                                                                  body::kSpine3,
                                                                  kNone,
                                                                  body::kLeftCollar,
                                                                  body::kLeftShoulder,
                                                                  body::kLeftElbow,
                                                                  body::kLeftWrist,
                                                                  body::kRightCollar,
                                                                  body::kRightShoulder,
                                                                  body::kRightElbow,
                                                                  body::kRightWrist,
                                                                  body::kPelvis,
                                                                  body::kLeftHip,
                                                                  body::kLeftKnee,
                                                                  kNone,
                                                                  body::kPelvis,
                                                                  body::kRightHip,
                                                                  body::kRightKnee,
                                                                  kNone,
                                                                  body::kSpine2,
                                                                  kNone,
                                                                  kNone,
                                                                  kNone,
                                                                  kNone};

constexpr double kHeadAboveSkullBase_m = 0.09;
constexpr double kThumbOffset_m = 0.04;

Eigen::Vector3d random_unit(SimRng& rng) {
  Eigen::Vector3d v;
  do {
    v = Eigen::Vector3d(rng.normal(), rng.normal(), rng.normal());
  } while (v.norm() < 1e-6);
  return v.normalized();
}

double uniform_in(SimRng& rng, double lo, double hi) { return lo + (hi - lo) * rng.uniform(); }

// Whether a face carried by SMPL joint `smpl_joint` is the camera joint's own surface, which
// does not hide it (CameraSkeletonSimulator, step 2). Limb joints lie within the margin of their
// surface, so only the trunk's joints have one.
bool is_own_surface(int camera_joint, int smpl_joint) {
  const bool trunk_surface = smpl_joint == body::kPelvis || smpl_joint == body::kSpine1 ||
                             smpl_joint == body::kSpine2 || smpl_joint == body::kSpine3 || smpl_joint == body::kNeck ||
                             smpl_joint == body::kLeftCollar || smpl_joint == body::kRightCollar;
  switch (camera_joint) {
    case kSpineBase:
    case kSpineMid:
    case kSpineShoulder:
    case kNeck: return trunk_surface;
    case kHipLeft: return trunk_surface || smpl_joint == body::kLeftHip;
    case kHipRight: return trunk_surface || smpl_joint == body::kRightHip;
    default: return false;
  }
}

void set_quaternion(const Eigen::Quaterniond& q, v1::Quaternion* out) {
  out->set_w(q.w());
  out->set_x(q.x());
  out->set_y(q.y());
  out->set_z(q.z());
}

}  // namespace

const std::array<int, kCameraJointCount>& camera_joint_parents() {
  static const std::array<int, kCameraJointCount> parents = {
      -1,         kSpineBase,     kSpineShoulder, kNeck,       kSpineShoulder, kShoulderLeft, kElbowLeft,
      kWristLeft, kSpineShoulder, kShoulderRight, kElbowRight, kWristRight,    kSpineBase,    kHipLeft,
      kKneeLeft,  kAnkleLeft,     kSpineBase,     kHipRight,   kKneeRight,     kAnkleRight,   kSpineMid,
      kHandLeft,  kHandLeft,      kHandRight,     kHandRight};
  return parents;
}

bool is_upper_limb(int j) { return (j >= kShoulderLeft && j <= kHandRight) || (j >= kHandTipLeft && j <= kThumbRight); }

void validate(const CameraSkeletonOptions& o) {
  require_interval(o.upper_limb_bias_min_m, o.upper_limb_bias_max_m, "upper_limb_bias_max_m");
  require_non_negative(o.upper_limb_bias_min_m, "upper_limb_bias_min_m");
  require_interval(o.other_bias_min_m, o.other_bias_max_m, "other_bias_max_m");
  require_non_negative(o.other_bias_min_m, "other_bias_min_m");
  require_positive(o.bias_period_s, "bias_period_s");
  require_non_negative(o.jitter_sigma_m, "jitter_sigma_m");
  require_non_negative(o.occlusion_margin_m, "occlusion_margin_m");
  require_non_negative(o.inferred_error_m, "inferred_error_m");
  require_non_negative(o.inferred_shoulder_drop_m, "inferred_shoulder_drop_m");
  if (!o.down_K.allFinite() || std::abs(o.down_K.norm() - 1.0) > 1e-6) {
    throw_invalid("down_K", "must be a finite unit vector");
  }
  require_probability(o.jump_probability, "jump_probability");
  require_probability(o.hand_flip_probability, "hand_flip_probability");
  require_interval(o.jump_min_m, o.jump_max_m, "jump_max_m");
  require_non_negative(o.jump_min_m, "jump_min_m");
}

SmplJointsK smpl_joints_in_camera(const body::BodyEvaluator& evaluator, const Eigen::Isometry3d& K_from_W) {
  SmplJointsK out;
  out.positions_K = K_from_W * evaluator.joints();
  for (int j = 0; j < body::kNumJoints; ++j) {
    out.K_from_joint[j] = K_from_W.linear() * evaluator.joint_rotation(j);
  }
  return out;
}

Eigen::Matrix3Xd camera_joints_from_smpl(const SmplJointsK& smpl) {
  if (smpl.positions_K.cols() != body::kNumJoints || !smpl.positions_K.allFinite()) {
    throw_invalid("positions_K",
                  "must hold 24 finite SMPL joints, got " + std::to_string(smpl.positions_K.cols()) + " columns");
  }
  // The same correspondence the fit reports its camera-compatible joints with.
  fit::JointPose pose;
  pose.positions_K = smpl.positions_K;
  pose.K_from_joint = smpl.K_from_joint;
  fit::CameraJointOptions options;
  options.head_above_skull_base_m = kHeadAboveSkullBase_m;
  options.thumb_offset_m = kThumbOffset_m;
  return fit::camera_joints_from_pose(pose, options);
}

CameraSkeletonSimulator::CameraSkeletonSimulator(const raycast::DepthCamera& camera,
                                                 const CameraSkeletonOptions& options, std::uint64_t seed,
                                                 const body::SmplModel& rendered)
    : camera_(camera), options_(options), seed_(seed) {
  validate(options);
  joint_of_face_.resize(static_cast<std::size_t>(rendered.num_faces()));
  for (int f = 0; f < rendered.num_faces(); ++f) {
    joint_of_face_[static_cast<std::size_t>(f)] =
        static_cast<std::int8_t>(body::dominant_joint(rendered, rendered.faces(0, f)));
  }
  SimRng rng(seed, "skeleton_bias");
  for (int j = 0; j < kCameraJointCount; ++j) {
    bias_length_m_[j] = is_upper_limb(j) ? uniform_in(rng, options.upper_limb_bias_min_m, options.upper_limb_bias_max_m)
                                         : uniform_in(rng, options.other_bias_min_m, options.other_bias_max_m);
    bias_u_[j] = random_unit(rng);
    bias_v_[j] = bias_u_[j].cross(random_unit(rng));
    if (bias_v_[j].norm() < 1e-6) bias_v_[j] = bias_u_[j].unitOrthogonal();
    bias_v_[j].normalize();
    bias_phase_[j] = 2 * pi * rng.uniform();
    inferred_direction_[j] = random_unit(rng);
  }
}

v1::SkeletonFrame CameraSkeletonSimulator::simulate(const SmplJointsK& smpl, const std::vector<uint16_t>& depth_mm,
                                                    const std::vector<std::int32_t>& face, std::int64_t frame_index,
                                                    std::int64_t t_us, std::uint32_t body_id) const {
  const int width = camera_.width(), height = camera_.height();
  const auto pixels = static_cast<std::size_t>(width) * height;
  if (depth_mm.size() != pixels) {
    throw_invalid("depth_mm",
                  "has " + std::to_string(depth_mm.size()) + " pixels, the camera " + std::to_string(pixels));
  }
  if (face.size() != pixels) {
    throw_invalid("face", "has " + std::to_string(face.size()) + " pixels, the camera " + std::to_string(pixels));
  }
  const auto faces = static_cast<std::int32_t>(joint_of_face_.size());
  if (const auto bad = std::find_if(face.begin(), face.end(), [&](std::int32_t f) { return f < -1 || f >= faces; });
      bad != face.end()) {
    throw_invalid("face", "pixel " + std::to_string(bad - face.begin()) + " holds face " + std::to_string(*bad) +
                              ", the rendered mesh has " + std::to_string(faces));
  }
  for (int j = 0; j < body::kNumJoints; ++j) {
    if (!smpl.K_from_joint[j].allFinite())
      throw_invalid("K_from_joint", "joint " + std::to_string(j) + " is not finite");
  }
  Eigen::Matrix3Xd truth = camera_joints_from_smpl(smpl);

  // 1. Straight spine.
  const Eigen::Vector3d base = truth.col(kSpineBase), top = truth.col(kSpineShoulder);
  const Eigen::Vector3d axis = top - base;
  if (axis.squaredNorm() > 1e-12) {
    const double s = std::clamp((truth.col(kSpineMid) - base).dot(axis) / axis.squaredNorm(), 0.0, 1.0);
    truth.col(kSpineMid) = base + s * axis;
  }

  const std::string frame_tag = "/" + std::to_string(frame_index);
  SimRng jitter_rng(seed_, "skeleton_jitter" + frame_tag);
  SimRng jump_rng(seed_, "skeleton_jump" + frame_tag);
  SimRng flip_rng(seed_, "skeleton_flip" + frame_tag);
  const double t_s = static_cast<double>(t_us) * 1e-6;

  Eigen::Matrix3Xd reported(3, kCameraJointCount);
  std::array<bool, kCameraJointCount> inferred{};
  for (int j = 0; j < kCameraJointCount; ++j) {
    const Eigen::Vector3d p = truth.col(j);
    // 2. Occlusion against the depth image.
    const std::optional<Eigen::Vector2d> uv = camera_.project(p);
    bool occluded = true;
    if (uv) {
      const long col = std::lround((*uv).x()), row = std::lround((*uv).y());
      if (col >= 0 && row >= 0 && col < width && row < height) {
        const std::size_t pixel = static_cast<std::size_t>(row) * width + col;
        const uint16_t d = depth_mm[pixel];
        const std::int32_t f = face[pixel];
        const bool own = f >= 0 && is_own_surface(j, joint_of_face_[static_cast<std::size_t>(f)]);
        occluded = d != 0 && d * 1e-3 < p.z() - options_.occlusion_margin_m && !own;
      }
    }
    inferred[j] = occluded;
    Eigen::Vector3d error = Eigen::Vector3d::Zero();
    if (occluded) {
      error += options_.inferred_error_m * inferred_direction_[j];
      if (j == kShoulderLeft || j == kShoulderRight) error += options_.inferred_shoulder_drop_m * options_.down_K;
    }
    // 3. Slow bias and jitter.
    const double angle = 2 * pi * t_s / options_.bias_period_s + bias_phase_[j];
    error += bias_length_m_[j] * (std::cos(angle) * bias_u_[j] + std::sin(angle) * bias_v_[j]);
    error += options_.jitter_sigma_m * Eigen::Vector3d(jitter_rng.normal(), jitter_rng.normal(), jitter_rng.normal());
    reported.col(j) = p + error;
  }
  // 4. A jump of one upper-limb joint.
  if (jump_rng.uniform() < options_.jump_probability) {
    static constexpr int kUpperLimb[12] = {kShoulderLeft,  kElbowLeft,  kWristLeft,    kHandLeft,
                                           kShoulderRight, kElbowRight, kWristRight,   kHandRight,
                                           kHandTipLeft,   kThumbLeft,  kHandTipRight, kThumbRight};
    const int j = kUpperLimb[std::min(11, static_cast<int>(jump_rng.uniform() * 12))];
    const double length = uniform_in(jump_rng, options_.jump_min_m, options_.jump_max_m);
    reported.col(j) += length * random_unit(jump_rng);
  }

  v1::SkeletonFrame frame;
  frame.set_t_us(t_us);
  frame.set_body_id(body_id);
  const auto& parents = camera_joint_parents();
  for (int j = 0; j < kCameraJointCount; ++j) {
    v1::SkeletonJoint* joint = frame.add_joints();
    joint->mutable_position_m()->set_x(reported(0, j));
    joint->mutable_position_m()->set_y(reported(1, j));
    joint->mutable_position_m()->set_z(reported(2, j));
    joint->set_state(inferred[j] ? v1::SkeletonJoint::INFERRED : v1::SkeletonJoint::TRACKED);
    const int bone = kSmplRotatingBone[j];
    if (bone == kNone) {
      set_quaternion(Eigen::Quaterniond(0, 0, 0, 0), joint->mutable_orientation());
      continue;
    }
    const Eigen::Matrix3d& R = smpl.K_from_joint[bone];
    Eigen::Matrix3d K_from_joint = R;
    if (parents[j] >= 0) {
      // Hierarchical: y along the reported bone, x from the SMPL bone rotation.
      const Eigen::Vector3d y = (reported.col(j) - reported.col(parents[j])).normalized();
      Eigen::Vector3d x = R.col(0) - R.col(0).dot(y) * y;
      if (x.norm() < 1e-6) x = R.col(2) - R.col(2).dot(y) * y;
      x.normalize();
      K_from_joint.col(0) = x;
      K_from_joint.col(1) = y;
      K_from_joint.col(2) = x.cross(y);
    }
    Eigen::Quaterniond q(K_from_joint);
    // 5. Hand flips about the bone.
    if ((j == kHandLeft || j == kHandRight) && flip_rng.uniform() < options_.hand_flip_probability) {
      q = q * Eigen::Quaterniond(Eigen::AngleAxisd(pi, Eigen::Vector3d::UnitY()));
    }
    q.normalize();
    set_quaternion(q, joint->mutable_orientation());
  }
  return frame;
}

}  // namespace posefuse::sim
