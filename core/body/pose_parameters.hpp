#pragma once
// Pose parameters theta of paper 2 (II-B) and the soft joint limits of its limit term (eq. 8).
//
// theta maps linearly onto SMPL's per-joint rotation vectors: each rotational DOF adds
// theta_d * axis_d to the rotation vector of its joint (axes in the parent's rest frame, i.e.
// SMPL's canonical frame because every rest rotation is the identity). Paper 2 removes the
// roll DOF (rotation about the bone) at every joint except the spine and the head; a joint
// with two DOF therefore rotates only about two axes perpendicular to its bone in the rest
// T-pose, i.e. pure swing without twist.
//
// Our reading of the DOF counts (the paper gives only the totals 40 and 48):
//   global translation 3 + global rotation 3 (pelvis)                      =  6
//   spine1, spine2, spine3, head: 3 each                                   = 12
//   neck: 2 (nod, side tilt)                                               =  2
//   left/right hip, collar, shoulder, elbow, wrist: 2 each                 = 20
//   upper body ("from the hips and above")                                 = 40
//   full body adds left/right knee and ankle, 2 each                       = 48
// Feet and hands (the orbs) have no DOF. The limits table in pose_parameters.cpp is the one
// documented place for the bounds psi_min, psi_max of eq. 8.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "body/smpl_model.hpp"

namespace posefuse::body {

enum class DofKind { kTranslation, kRotation };

struct Dof {
  DofKind kind = DofKind::kRotation;
  int joint = 0;                    // SMPL joint (0 for the global translation)
  Eigen::Vector3d axis;             // unit axis: translation direction or rotation axis (parent frame)
  std::string name;                 // e.g. "left_elbow_y"
  bool limited = false;             // global DOF are not limited (eq. 8 sums over N_theta - 6)
  double min_rad = 0, max_rad = 0;  // soft limits for eq. 8
};

class PoseLayout {
 public:
  static PoseLayout upper_body();  // 40 DOF
  static PoseLayout full_body();   // 48 DOF
  // Every joint with 3 DOF plus translation (75): plain SMPL, used to test the skinning.
  static PoseLayout all_joints();

  int size() const { return static_cast<int>(dofs_.size()); }
  const Dof& dof(int d) const { return dofs_[d]; }
  const std::vector<Dof>& dofs() const { return dofs_; }
  // DOF indices of one joint, in increasing order (joint 0 also owns the translation).
  const std::vector<int>& dofs_of_joint(int joint) const { return dofs_of_joint_[joint]; }
  int index_of(const std::string& name) const;  // throws when absent

  // SMPL rotation vectors (3 x 24) and translation for a theta of this layout.
  void to_smpl(const Eigen::Ref<const Eigen::VectorXd>& theta, Eigen::Matrix3Xd& rotation_vectors,
               Eigen::Vector3d& translation) const;
  // The zero pose (rest T-pose at the origin).
  Eigen::VectorXd zero() const { return Eigen::VectorXd::Zero(size()); }

 private:
  explicit PoseLayout(std::vector<Dof> dofs);
  std::vector<Dof> dofs_;
  std::vector<std::vector<int>> dofs_of_joint_;
};

}  // namespace posefuse::body
