#pragma once
// Linear blend skinning of an SMPL-format model with analytic derivatives (paper 2, II-B).
//
//   v_shaped = v_template + shapedirs * beta
//   J        = J_regressor * v_shaped                      (rest joints)
//   v_posed  = v_shaped + posedirs * vec(R_loc(j) - I)     (only when the model has posedirs)
//   R(j)     = R(parent) * R_loc(j),  c(j) = c(parent) + R(parent) (J(j) - J(parent))
//   v        = sum_k w_k (R(k) (v_posed - J(k)) + c(k)),   c(0) = J(0) + translation
//
// Derivatives. A rotational DOF d of joint j turns everything below j about the posed joint
// c(j) with the world angular rate W_d = R(parent(j)) J_l(omega_j) axis_d (J_l: left Jacobian of
// SO(3)), so d v / d theta_d = W_d x sum_{k below j} w_k (R(k)(v_posed - J(k)) + c(k) - c(j)).
// Each vertex therefore depends only on the DOFs of the ancestors of its skinning joints; its
// pose Jacobian is stored as a dense 3 x n block over exactly those n DOFs (n <= 30 for the
// upper-body layout), computed without allocation after construction.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "body/pose_parameters.hpp"
#include "body/smpl_model.hpp"

namespace posefuse::body {

// kPoseOnRequest: the joints' pose Jacobian now, the vertices' pose Jacobians only for the
// vertices later passed to compute_vertex_pose_jacobians() (a fit that uses a part of the mesh).
enum class Derivatives { kNone, kPose, kPoseAndShape, kPoseOnRequest };

class BodyEvaluator {
 public:
  // Validates the model. The evaluator keeps its own reference to the model.
  BodyEvaluator(std::shared_ptr<const SmplModel> model, PoseLayout layout);

  // Poses the model; beta has model.num_betas() entries (fewer are padded with zeros),
  // theta has layout.size(). Throws posefuse::Error for wrong sizes or non-finite values.
  void evaluate(const Eigen::Ref<const Eigen::VectorXd>& beta, const Eigen::Ref<const Eigen::VectorXd>& theta,
                Derivatives what);

  const SmplModel& model() const { return *model_; }
  const PoseLayout& layout() const { return layout_; }

  const Eigen::Matrix3Xd& vertices() const { return vertices_; }                // 3 x V, posed
  const Eigen::Matrix3Xd& joints() const { return joints_; }                    // 3 x 24, posed
  const Eigen::Matrix3Xd& rest_joints() const { return rest_joints_; }          // 3 x 24, shaped
  const Eigen::Matrix3d& joint_rotation(int j) const { return rotations_[j]; }  // global R(j)

  // Jacobians below belong to the last evaluate() that asked for them (Derivatives::kPose or
  // kPoseAndShape); an evaluate() with fewer derivatives leaves them stale.
  // Pose Jacobian of vertex i: d vertex / d theta[vertex_dofs(i)[c]] is column c.
  std::span<const int> vertex_dofs(int i) const {
    return {dof_index_.data() + dof_begin_[i], static_cast<size_t>(dof_begin_[i + 1] - dof_begin_[i])};
  }
  Eigen::Map<const Eigen::Matrix3Xd> vertex_pose_jacobian(int i) const {
    return {pose_columns_.data() + 3 * dof_begin_[i], 3, dof_begin_[i + 1] - dof_begin_[i]};
  }
  // d joint / d theta: rows 3j..3j+2 belong to joint j (72 x N).
  const Eigen::MatrixXd& joint_pose_jacobian() const { return joint_pose_jacobian_; }
  // d vertex i / d beta, 3 x B (valid after Derivatives::kPoseAndShape).
  Eigen::Map<const Eigen::Matrix3Xd> vertex_shape_jacobian(int i) const {
    return {shape_columns_.data() + 3 * num_betas_ * i, 3, num_betas_};
  }
  // d joint / d beta, 72 x B.
  const Eigen::MatrixXd& joint_shape_jacobian() const { return joint_shape_jacobian_; }

  // After evaluate(..., kPoseOnRequest): the pose Jacobians of these vertices (the others stay
  // stale), the same values evaluate(..., kPose) gives. Does not allocate.
  void compute_vertex_pose_jacobians(std::span<const int> vertices);

  // Adds scale * d vertex(i) / d theta into the dense 3 x N block `out`.
  void add_vertex_pose_jacobian(int i, double scale, Eigen::Ref<Eigen::Matrix3Xd> out) const;
  // Adds m * d vertex(i) / d theta into `out` (m: 3 x 3), leaving out the DOFs of the joints in
  // the bit mask skip_joints (bit j: joint j).
  void add_vertex_pose_jacobian(int i, const Eigen::Matrix3d& m, Eigen::Ref<Eigen::Matrix3Xd> out,
                                std::uint32_t skip_joints = 0) const;
  // World angular rate W_d of rotational DOF d (see above); valid after any evaluate().
  const Eigen::Vector3d& dof_rate(int d) const { return dof_rate_[d]; }

 private:
  void update_shape(const Eigen::Ref<const Eigen::VectorXd>& beta);
  void update_transforms(const Eigen::Ref<const Eigen::VectorXd>& theta);
  // Vertex i's pose Jacobian columns (from the current transforms and v_posed_).
  void compute_vertex_pose_jacobian(int i);

  std::shared_ptr<const SmplModel> model_;
  PoseLayout layout_;
  int num_vertices_ = 0;
  int num_betas_ = 0;

  // Sparse skinning weights per vertex.
  std::vector<int> weight_begin_, weight_joint_;
  std::vector<double> weight_value_;
  // Joints whose DOFs move each vertex (ancestors of its skinning joints), ascending.
  std::vector<int> influence_begin_, influence_joint_;
  // Pose Jacobian layout: DOFs of each vertex, in the order of its influence joints.
  std::vector<int> dof_begin_, dof_index_;

  // Shape state (cached while beta does not change).
  Eigen::VectorXd beta_;
  bool shape_valid_ = false;
  Eigen::VectorXd v_shaped_;               // 3V
  Eigen::VectorXd v_posed_;                // 3V
  Eigen::Matrix3Xd rest_joints_;           // 3 x 24
  Eigen::MatrixXd rest_joint_shape_dirs_;  // 72 x B, J_regressor * shapedirs

  // Pose state.
  Eigen::Matrix3Xd rotation_vectors_;
  Eigen::Vector3d translation_;
  std::vector<Eigen::Matrix3d> local_rotations_, rotations_;
  std::vector<Eigen::Matrix3d> left_jacobians_;
  std::vector<char> dof_is_translation_;
  std::vector<Eigen::Vector3d> dof_rate_;                       // W_d per DOF (world frame)
  std::vector<Eigen::Matrix3d> dof_local_rotation_derivative_;  // d R_loc / d theta_d
  Eigen::Matrix3Xd joints_;
  std::array<Eigen::Vector3d, kNumJoints> offsets_;  // x -> R(k) x + offsets_[k], offsets_[k] = c(k) - R(k) J(k)

  // Outputs.
  Eigen::Matrix3Xd vertices_;
  std::vector<double> pose_columns_;
  Eigen::MatrixXd joint_pose_jacobian_;
  std::vector<double> shape_columns_;
  Eigen::MatrixXd joint_shape_jacobian_;
};

// Rotation matrix exp([omega]x) and the left Jacobian J_l(omega) of SO(3).
Eigen::Matrix3d rotation_from_vector(const Eigen::Vector3d& omega);
Eigen::Matrix3d so3_left_jacobian(const Eigen::Vector3d& omega);

}  // namespace posefuse::body
