#include "fit/fitted_body_frame.hpp"

#include <algorithm>
#include <array>
#include <numbers>
#include <vector>

#include "body/smpl_model.hpp"
#include "common/error.hpp"
#include "fit/camera_joints.hpp"
#include "fit/joint_kinematics.hpp"
#include "forearm/orientation_uncertainty.hpp"

namespace posefuse::fit {

namespace {

// Where the camera does not track a joint (inferred or lost) the fit places it from the depth
// around it and the body model. Measured on the joint-angle bench's design sessions
// (bench/untracked_joint_angles.py on bench/joint_angles.sh's seeds 61 and 62), with the
// untracked joint the only one among an angle's joints: the elbow flexions and humerus axial
// rotations read from an untracked wrist reach a 99 % error bound of 95 degrees, confidence
// 2^-(95/15)^2, i.e. none (forearm::confidence_from_bound99_rad); so an untracked wrist or hand
// passes on none. The angles read from an untracked elbow stay within 10.7 degrees, within the
// 15 of a confident value; an untracked joint other than the hand's keeps the weaker evidence's
// 0.5 (docs/benchmarks.md, "Angles read from untracked joints").
constexpr double kUntrackedConfidence = 0.5;
constexpr double kUntrackedHandConfidence = 0.0;
// A joint the camera tracks but puts more than kCameraDisagreementM from the fit is a different
// case from one the camera cannot see: there the camera's own view contradicts the fit. Unless
// the camera has gone off track (its error beyond 0.29 m in one value in 10^4), the fitted joint
// is itself about 0.29 - 0.101 = 0.19 m or more from the truth (0.101 m: the camera's published
// mean error), which turns a 0.3 m segment by some 30 degrees: a 99 % bound of that size has
// confidence 2^-(30/15)^2 = 0.06, i.e. none (the untracked elbow's 0.5 was measured where
// nothing contradicted the fit; docs/fitting.md, "Joint confidence").
constexpr double kOffCameraConfidence = 0.0;

// A fitted joint outside the depth image was placed by the kinematic chain from what the image
// shows, with no observation of its own: less than an untracked wrist has (whose arm the depth
// still sees, and which already has none).
constexpr double kOutOfViewConfidence = 0.0;

bool in_view(const raycast::DepthCamera& camera, const Eigen::Vector3d& p_K) {
  const auto px = camera.project(p_K);
  return px && px->x() >= 0 && px->x() < camera.width() && px->y() >= 0 && px->y() < camera.height();
}

bool is_hand_joint(int camera_joint) {
  switch (camera_joint) {
    case kWristLeft:
    case kHandLeft:
    case kHandTipLeft:
    case kThumbLeft:
    case kWristRight:
    case kHandRight:
    case kHandTipRight:
    case kThumbRight: return true;
    default: return false;
  }
}

// Whether the camera has a joint that is an SMPL joint (smpl_joint_at_camera_joint) far from
// where the fit has it (kCameraDisagreementM). The camera joints the fit derives (hand tips,
// thumbs, head, spine shoulder) are compared with nothing: the published error is that of the
// joints themselves.
bool far_from_fit(const TrackedSkeleton& skeleton, int camera_joint, const Eigen::Vector3d& fitted_K) {
  return smpl_joint_at_camera_joint(camera_joint) >= 0 &&
         !((skeleton.positions_K[static_cast<size_t>(camera_joint)] - fitted_K).norm() <= kCameraDisagreementM);
}

// An SMPL joint the camera has no joint for (spine1, spine3, the collars, the head) is placed by
// the fit between joints the camera has, so it is trusted no more than the least trusted of them:
// the nearest such joint towards the root and the nearest ones down each of its branches.
void bound_by_neighbours(std::array<double, body::kNumJoints>& confidence,
                         const std::array<bool, body::kNumJoints>& from_camera) {
  const auto& parents = body::kSmplParents;
  const std::array<double, body::kNumJoints> own = confidence;
  for (int j = 0; j < body::kNumJoints; ++j) {
    if (from_camera[static_cast<size_t>(j)]) continue;
    double bound = 1.0;
    int up = parents[static_cast<size_t>(j)];
    while (up >= 0 && !from_camera[static_cast<size_t>(up)]) up = parents[static_cast<size_t>(up)];
    if (up >= 0) bound = own[static_cast<size_t>(up)];
    std::vector<int> below = {j};
    while (!below.empty()) {
      const int k = below.back();
      below.pop_back();
      for (int child = k + 1; child < body::kNumJoints; ++child) {  // a parent has a lower id
        if (parents[static_cast<size_t>(child)] != k) continue;
        if (from_camera[static_cast<size_t>(child)]) bound = std::min(bound, own[static_cast<size_t>(child)]);
        else below.push_back(child);
      }
    }
    confidence[static_cast<size_t>(j)] = bound;
  }
}

// II-B: the forearm's IMU orientation turned onto the fitted axis, and its roll from the IMU.
FittedForearm fitted_forearm(const JointPose& pose, ArmSide side, const Eigen::Quaterniond& K_from_F,
                             double wrist_confidence) {
  const bool left = side == ArmSide::kLeft;
  const int elbow = left ? body::kLeftElbow : body::kRightElbow, wrist = left ? body::kLeftWrist : body::kRightWrist;
  const Eigen::Vector3d axis_K = (pose.positions_K.col(wrist) - pose.positions_K.col(elbow)).normalized();
  const Eigen::Quaterniond onto_fit = Eigen::Quaterniond::FromTwoVectors(K_from_F * Eigen::Vector3d::UnitY(), axis_K);
  FittedForearm forearm{side, (onto_fit * K_from_F).normalized(), 0.0, wrist_confidence};
  try {
    ArmRollOptions roll_options;
    roll_options.thumb_F = thumb_axis_F(side);
    const ForearmRoll roll = forearm_roll(pose, side, K_from_F, Eigen::Quaterniond::Identity(), roll_options);
    if (roll.pronation_rad) forearm.pronation_rad = *roll.pronation_rad;
  } catch (const Error&) {
    forearm.confidence = 0.0;  // roll undefined (IMU thumb axis along the fitted forearm)
  }
  return forearm;
}

}  // namespace

FittedBodyFrame make_fitted_body_frame(const Eigen::Matrix3Xd& rest_joints, const body::PoseLayout& layout,
                                       const Eigen::VectorXd& theta, const TrackedSkeleton& skeleton,
                                       const raycast::DepthCamera& camera, const ForearmOrientationPair& K_from_F) {
  const JointPose pose = pose_joints(rest_joints, layout, theta);
  const Eigen::Matrix3Xd camera_joints = camera_joints_from_pose(pose);
  FittedBodyFrame out;
  std::array<double, kKinectJointCount> camera_confidence;
  for (int j = 0; j < kKinectJointCount; ++j) {
    const bool tracked = skeleton.tracking[static_cast<size_t>(j)] == JointTracking::kTracked;
    const bool off_camera = tracked && far_from_fit(skeleton, j, camera_joints.col(j));
    if (off_camera) ++out.joints_off_camera;
    const bool out_of_view = !in_view(camera, camera_joints.col(j));
    if (out_of_view) ++out.joints_out_of_view;
    camera_confidence[static_cast<size_t>(j)] = out_of_view        ? kOutOfViewConfidence
                                                : off_camera       ? kOffCameraConfidence
                                                : tracked          ? 1.0
                                                : is_hand_joint(j) ? kUntrackedHandConfidence
                                                                   : kUntrackedConfidence;
    out.camera_joints.push_back({camera_joints.col(j), camera_confidence[static_cast<size_t>(j)]});
  }
  std::array<double, body::kNumJoints> smpl_confidence;
  std::array<bool, body::kNumJoints> from_camera{};
  smpl_confidence.fill(1.0);
  for (int j = 0; j < kKinectJointCount; ++j) {
    const int smpl = smpl_joint_at_camera_joint(j);
    if (smpl < 0) continue;
    smpl_confidence[static_cast<size_t>(smpl)] = camera_confidence[static_cast<size_t>(j)];
    from_camera[static_cast<size_t>(smpl)] = true;
  }
  bound_by_neighbours(smpl_confidence, from_camera);
  for (int j = 0; j < body::kNumJoints; ++j) {
    out.smpl_joints.push_back({pose.positions_K.col(j), smpl_confidence[static_cast<size_t>(j)]});
  }
  for (int j = 0; j < body::kNumJoints; ++j) out.K_from_joint.emplace_back(pose.K_from_joint[static_cast<size_t>(j)]);
  if (K_from_F.left)
    out.forearms.push_back(fitted_forearm(pose, ArmSide::kLeft, *K_from_F.left, camera_confidence[kWristLeft]));
  if (K_from_F.right)
    out.forearms.push_back(fitted_forearm(pose, ArmSide::kRight, *K_from_F.right, camera_confidence[kWristRight]));
  return out;
}

double untrusted_fit_confidence() {
  return forearm::confidence_from_bound99_rad(kUntrustedFitBound99Deg * std::numbers::pi / 180.0);
}

void cap_confidence(FittedBodyFrame& frame, double cap) {
  for (auto* joints : {&frame.smpl_joints, &frame.camera_joints}) {
    for (FittedJoint& j : *joints) j.confidence = std::min(j.confidence, cap);
  }
  for (FittedForearm& f : frame.forearms) f.confidence = std::min(f.confidence, cap);
}

}  // namespace posefuse::fit
