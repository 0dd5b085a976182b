#include "body/pose_parameters.hpp"

#include <cmath>
#include <numbers>

#include "common/error.hpp"

namespace posefuse::body {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// One rotational DOF: joint, axis (x=0, y=1, z=2), limits in degrees.
struct LimitRow {
  int joint;
  int axis;
  double min_deg, max_deg;
};

// Soft joint limits (paper 2, eq. 8), degrees, as rotation-vector components about the axes of
// SMPL's canonical frame (x subject's left, y up, z front) at the rest T-pose. Signs follow the
// right-hand rule: a positive x rotation bends the spine forward; a positive z rotation raises
// the left arm and lowers the right arm; a negative y rotation swings the left arm forward,
// a positive one the right arm. Ranges are typical active ranges of motion of adults, widened a
// little because the limit term is soft.
constexpr LimitRow kLimits[] = {
    {kSpine1, 0, -25, 45},
    {kSpine1, 1, -30, 30},
    {kSpine1, 2, -25, 25},
    {kSpine2, 0, -20, 35},
    {kSpine2, 1, -25, 25},
    {kSpine2, 2, -20, 20},
    {kSpine3, 0, -20, 35},
    {kSpine3, 1, -25, 25},
    {kSpine3, 2, -20, 20},
    {kNeck, 0, -40, 50},
    {kNeck, 2, -35, 35},
    {kHead, 0, -30, 40},
    {kHead, 1, -70, 70},
    {kHead, 2, -30, 30},
    // Left/right pairs mirror their y and z ranges.
    {kLeftCollar, 1, -20, 20},
    {kLeftCollar, 2, -15, 30},
    {kRightCollar, 1, -20, 20},
    {kRightCollar, 2, -30, 15},
    {kLeftShoulder, 1, -120, 50},
    {kLeftShoulder, 2, -95, 95},
    {kRightShoulder, 1, -50, 120},
    {kRightShoulder, 2, -95, 95},
    {kLeftElbow, 1, -155, 10},
    {kLeftElbow, 2, -30, 30},
    {kRightElbow, 1, -10, 155},
    {kRightElbow, 2, -30, 30},
    {kLeftWrist, 1, -80, 80},
    {kLeftWrist, 2, -45, 45},
    {kRightWrist, 1, -80, 80},
    {kRightWrist, 2, -45, 45},
    // Legs hang along -y: x is flexion (negative = hip forward, positive = knee back).
    {kLeftHip, 0, -120, 30},
    {kLeftHip, 2, -25, 50},
    {kRightHip, 0, -120, 30},
    {kRightHip, 2, -50, 25},
    {kLeftKnee, 0, -5, 150},
    {kLeftKnee, 2, -10, 10},
    {kRightKnee, 0, -5, 150},
    {kRightKnee, 2, -10, 10},
    {kLeftAnkle, 0, -45, 30},
    {kLeftAnkle, 2, -25, 25},
    {kRightAnkle, 0, -45, 30},
    {kRightAnkle, 2, -25, 25},
};

// The elbows of the layouts without arm roll (upper_body, full_body). Paper 2 (II-B) drops the
// roll DOF of the arm joints, so the upper arm cannot turn about itself (humeral rotation), and
// the elbow's swing has to carry it: flexion phi with the humerus turned by alpha from the T-pose's
// palms-down reference is the swing phi (-cos alpha, sin alpha) about (y, z) on the left arm
// (mirrored on the right). With kLimits' anatomical ranges (z +-30 deg) the poses of paper 1's
// protocol were out of reach: the calibration pose (upper arm sideways, forearm vertical: z = 90 deg),
// the forearm behind the head (external rotation beyond 90 deg) and behind the back (internal
// rotation beyond 90 deg), and the fit paid for them with 13-40 cm wrist errors
// (docs/fitting.md, "Paper 1's protocol"). z covers rotation up to +-90 deg at 150 deg of flexion;
// the extension side of y reaches 60 deg, the swing of flexion ~120 deg with the humerus turned
// ~120 deg (chosen on paper 1's protocol among 10, 30, 45, 60 and 90 deg).
constexpr LimitRow kNoRollElbowLimits[] = {
    {kLeftElbow, 1, -155, 60},
    {kLeftElbow, 2, -150, 150},
    {kRightElbow, 1, -60, 155},
    {kRightElbow, 2, -150, 150},
};

Dof rotation_dof(int joint, int axis) {
  Dof d;
  d.kind = DofKind::kRotation;
  d.joint = joint;
  d.axis = Eigen::Vector3d::Unit(axis);
  d.name = std::string(smpl_joint_names()[joint]) + "_" + "xyz"[axis];
  for (const LimitRow& row : kLimits)
    if (row.joint == joint && row.axis == axis) {
      d.limited = true;
      d.min_rad = row.min_deg * kDeg;
      d.max_rad = row.max_deg * kDeg;
    }
  return d;
}

std::vector<Dof> global_dofs() {
  std::vector<Dof> dofs;
  for (int a = 0; a < 3; ++a) {
    Dof t;
    t.kind = DofKind::kTranslation;
    t.joint = kPelvis;
    t.axis = Eigen::Vector3d::Unit(a);
    t.name = std::string("translation_") + "xyz"[a];
    dofs.push_back(t);
  }
  for (int a = 0; a < 3; ++a) dofs.push_back(rotation_dof(kPelvis, a));
  return dofs;
}

void add_joint(std::vector<Dof>& dofs, int joint, std::initializer_list<int> axes) {
  for (int a : axes) dofs.push_back(rotation_dof(joint, a));
}

void add_upper_body(std::vector<Dof>& dofs) {
  for (int j : {kLeftHip, kRightHip}) add_joint(dofs, j, {0, 2});
  for (int j : {kSpine1, kSpine2, kSpine3}) add_joint(dofs, j, {0, 1, 2});
  add_joint(dofs, kNeck, {0, 2});
  add_joint(dofs, kHead, {0, 1, 2});
  // Arm bones run along x in the T-pose: swing about y and z, no roll about x.
  for (int j :
       {kLeftCollar, kRightCollar, kLeftShoulder, kRightShoulder, kLeftElbow, kRightElbow, kLeftWrist, kRightWrist})
    add_joint(dofs, j, {1, 2});
  for (Dof& d : dofs)
    for (const LimitRow& row : kNoRollElbowLimits)
      if (d.kind == DofKind::kRotation && d.joint == row.joint && d.axis == Eigen::Vector3d::Unit(row.axis)) {
        d.min_rad = row.min_deg * kDeg;
        d.max_rad = row.max_deg * kDeg;
      }
}

}  // namespace

PoseLayout::PoseLayout(std::vector<Dof> dofs) : dofs_(std::move(dofs)), dofs_of_joint_(kNumJoints) {
  for (int d = 0; d < size(); ++d) dofs_of_joint_[dofs_[d].joint].push_back(d);
}

PoseLayout PoseLayout::upper_body() {
  std::vector<Dof> dofs = global_dofs();
  add_upper_body(dofs);
  return PoseLayout(std::move(dofs));
}

PoseLayout PoseLayout::full_body() {
  std::vector<Dof> dofs = global_dofs();
  add_upper_body(dofs);
  for (int j : {kLeftKnee, kRightKnee, kLeftAnkle, kRightAnkle}) add_joint(dofs, j, {0, 2});
  return PoseLayout(std::move(dofs));
}

PoseLayout PoseLayout::all_joints() {
  std::vector<Dof> dofs = global_dofs();
  for (int j = 1; j < kNumJoints; ++j) add_joint(dofs, j, {0, 1, 2});
  return PoseLayout(std::move(dofs));
}

int PoseLayout::index_of(const std::string& name) const {
  for (int d = 0; d < size(); ++d)
    if (dofs_[d].name == name) return d;
  throw Error(ErrorCode::kNotFound, "dof", "no DOF named '" + name + "' in this layout");
}

void PoseLayout::to_smpl(const Eigen::Ref<const Eigen::VectorXd>& theta, Eigen::Matrix3Xd& rotation_vectors,
                         Eigen::Vector3d& translation) const {
  if (theta.size() != size())
    throw_invalid("theta", "size " + std::to_string(theta.size()) + ", layout has " + std::to_string(size()) + " DOF");
  rotation_vectors.setZero(3, kNumJoints);
  translation.setZero();
  for (int d = 0; d < size(); ++d) {
    if (!std::isfinite(theta[d])) throw_invalid("theta[" + std::to_string(d) + "]", "not finite");
    const Dof& dof = dofs_[d];
    if (dof.kind == DofKind::kTranslation) translation += theta[d] * dof.axis;
    else rotation_vectors.col(dof.joint) += theta[d] * dof.axis;
  }
}

}  // namespace posefuse::body
