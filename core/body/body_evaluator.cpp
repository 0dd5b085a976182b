#include "body/body_evaluator.hpp"

#include <Eigen/Geometry>
#include <cmath>

#include "common/error.hpp"

namespace posefuse::body {

Eigen::Matrix3d rotation_from_vector(const Eigen::Vector3d& omega) {
  const double angle = omega.norm();
  if (angle < 1e-12) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, omega / angle).toRotationMatrix();
}

namespace {
Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}
}  // namespace

Eigen::Matrix3d so3_left_jacobian(const Eigen::Vector3d& omega) {
  const double angle = omega.norm();
  const Eigen::Matrix3d k = skew(omega);
  if (angle < 1e-6) return Eigen::Matrix3d::Identity() + 0.5 * k + (1.0 / 6.0) * k * k;
  const double a2 = angle * angle;
  return Eigen::Matrix3d::Identity() + (1 - std::cos(angle)) / a2 * k +
         (angle - std::sin(angle)) / (a2 * angle) * k * k;
}

BodyEvaluator::BodyEvaluator(std::shared_ptr<const SmplModel> model, PoseLayout layout)
    : model_(std::move(model)), layout_(std::move(layout)) {
  if (!model_) throw_invalid("model", "is null");
  validate(*model_);
  const SmplModel& m = *model_;
  num_vertices_ = m.num_vertices();
  num_betas_ = m.num_betas();

  weight_begin_.assign(1, 0);
  influence_begin_.assign(1, 0);
  dof_begin_.assign(1, 0);
  for (int i = 0; i < num_vertices_; ++i) {
    std::array<bool, kNumJoints> influences{};
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(m.weights, i); it; ++it) {
      if (it.value() == 0.0) continue;
      weight_joint_.push_back(static_cast<int>(it.col()));
      weight_value_.push_back(it.value());
      for (int j = static_cast<int>(it.col()); j >= 0; j = m.parents[j]) influences[j] = true;
    }
    // Pose correctives couple every joint's rotation into every vertex.
    if (m.has_posedirs()) influences.fill(true);
    for (int j = 0; j < kNumJoints; ++j) {
      if (!influences[j]) continue;
      influence_joint_.push_back(j);
      for (int d : layout_.dofs_of_joint(j)) dof_index_.push_back(d);
    }
    weight_begin_.push_back(static_cast<int>(weight_joint_.size()));
    influence_begin_.push_back(static_cast<int>(influence_joint_.size()));
    dof_begin_.push_back(static_cast<int>(dof_index_.size()));
  }

  rest_joint_shape_dirs_.resize(3 * kNumJoints, num_betas_);
  for (int b = 0; b < num_betas_; ++b) {
    const Eigen::Map<const Eigen::Matrix3Xd> dir(m.shapedirs.col(b).data(), 3, num_vertices_);
    const Eigen::Matrix3Xd joint_dir = dir * m.J_regressor.transpose();
    rest_joint_shape_dirs_.col(b) = Eigen::Map<const Eigen::VectorXd>(joint_dir.data(), 3 * kNumJoints);
  }

  beta_.setZero(num_betas_);
  v_shaped_.resize(3 * num_vertices_);
  v_posed_.resize(3 * num_vertices_);
  rest_joints_.resize(3, kNumJoints);
  local_rotations_.resize(kNumJoints);
  rotations_.resize(kNumJoints);
  left_jacobians_.resize(kNumJoints);
  dof_rate_.resize(layout_.size());
  for (const Dof& dof : layout_.dofs()) dof_is_translation_.push_back(dof.kind == DofKind::kTranslation);
  dof_local_rotation_derivative_.resize(layout_.size());
  joints_.resize(3, kNumJoints);
  vertices_.resize(3, num_vertices_);
  pose_columns_.assign(3 * dof_index_.size(), 0.0);
  joint_pose_jacobian_.setZero(3 * kNumJoints, layout_.size());
  shape_columns_.assign(3 * static_cast<size_t>(num_betas_) * num_vertices_, 0.0);
  joint_shape_jacobian_.setZero(3 * kNumJoints, num_betas_);
}

void BodyEvaluator::update_shape(const Eigen::Ref<const Eigen::VectorXd>& beta) {
  if (beta.size() > num_betas_)
    throw_invalid("beta", "size " + std::to_string(beta.size()) + ", model has " + std::to_string(num_betas_) +
                              " shape directions");
  // Compared in place: evaluate() must not allocate on the fitter's hot path.
  bool same = shape_valid_;
  for (Eigen::Index b = 0; b < num_betas_; ++b) {
    const double value = b < beta.size() ? beta[b] : 0.0;
    if (!std::isfinite(value)) throw_invalid("beta[" + std::to_string(b) + "]", "not finite");
    same = same && value == beta_[b];
  }
  if (same) return;
  beta_.setZero();
  beta_.head(beta.size()) = beta;
  const SmplModel& m = *model_;
  v_shaped_ = Eigen::Map<const Eigen::VectorXd>(m.v_template.data(), 3 * num_vertices_);
  if (num_betas_ > 0) v_shaped_.noalias() += m.shapedirs * beta_;
  const Eigen::Map<const Eigen::Matrix3Xd> shaped(v_shaped_.data(), 3, num_vertices_);
  rest_joints_.noalias() = shaped * m.J_regressor.transpose();
  shape_valid_ = true;
}

void BodyEvaluator::update_transforms(const Eigen::Ref<const Eigen::VectorXd>& theta) {
  layout_.to_smpl(theta, rotation_vectors_, translation_);
  const auto& parents = model_->parents;
  for (int j = 0; j < kNumJoints; ++j) {
    const Eigen::Vector3d omega = rotation_vectors_.col(j);
    local_rotations_[j] = rotation_from_vector(omega);
    left_jacobians_[j] = so3_left_jacobian(omega);
    const int p = parents[j];
    if (p < 0) {
      rotations_[j] = local_rotations_[j];
      joints_.col(j) = rest_joints_.col(j) + translation_;
    } else {
      rotations_[j] = rotations_[p] * local_rotations_[j];
      joints_.col(j) = joints_.col(p) + rotations_[p] * (rest_joints_.col(j) - rest_joints_.col(p));
    }
  }
  for (int d = 0; d < layout_.size(); ++d) {
    const Dof& dof = layout_.dof(d);
    if (dof.kind != DofKind::kRotation) continue;
    const int j = dof.joint;
    const Eigen::Vector3d local_rate = left_jacobians_[j] * dof.axis;
    const int p = parents[j];
    dof_rate_[d] = p < 0 ? local_rate : Eigen::Vector3d(rotations_[p] * local_rate);
    dof_local_rotation_derivative_[d] = skew(local_rate) * local_rotations_[j];
  }
}

void BodyEvaluator::evaluate(const Eigen::Ref<const Eigen::VectorXd>& beta,
                             const Eigen::Ref<const Eigen::VectorXd>& theta, Derivatives what) {
  update_shape(beta);
  update_transforms(theta);
  const SmplModel& m = *model_;

  // Pose-corrective offsets (SMPL): features are (R_loc - I) row-major for joints 1..23.
  v_posed_ = v_shaped_;
  if (m.has_posedirs()) {
    Eigen::Matrix<double, kNumPoseFeatures, 1> features;
    for (int j = 1; j < kNumJoints; ++j)
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
          features[9 * (j - 1) + 3 * r + c] = local_rotations_[j](r, c) - (r == c ? 1.0 : 0.0);
    v_posed_.noalias() += m.posedirs * features;
  }

  // Per joint: x -> R(k) x + (c(k) - R(k) J(k)).
  for (int k = 0; k < kNumJoints; ++k) offsets_[k] = joints_.col(k) - rotations_[k] * rest_joints_.col(k);

  const bool pose_derivatives = what != Derivatives::kNone;
  const bool vertex_pose_derivatives = what == Derivatives::kPose || what == Derivatives::kPoseAndShape;
  const bool shape_derivatives = what == Derivatives::kPoseAndShape;
  const auto& parents = m.parents;

  // d c(k) / d beta (72 x B), needed for the shape Jacobian.
  if (shape_derivatives) {
    for (int k = 0; k < kNumJoints; ++k) {
      const int p = parents[k];
      for (int b = 0; b < num_betas_; ++b) {  // column by column: no temporaries
        const Eigen::Vector3d rest_dir = rest_joint_shape_dirs_.block<3, 1>(3 * k, b);
        joint_shape_jacobian_.block<3, 1>(3 * k, b) =
            p < 0 ? rest_dir
                  : Eigen::Vector3d(joint_shape_jacobian_.block<3, 1>(3 * p, b) +
                                    rotations_[p] * (rest_dir - rest_joint_shape_dirs_.block<3, 1>(3 * p, b)));
      }
    }
  }

  for (int i = 0; i < num_vertices_; ++i) {
    const Eigen::Vector3d rest = v_posed_.segment<3>(3 * i);
    Eigen::Vector3d v = Eigen::Vector3d::Zero();
    for (int e = weight_begin_[i]; e < weight_begin_[i + 1]; ++e) {
      const int k = weight_joint_[e];
      v += weight_value_[e] * (rotations_[k] * rest + offsets_[k]);
    }
    vertices_.col(i) = v;
    if (vertex_pose_derivatives) compute_vertex_pose_jacobian(i);
    if (shape_derivatives) {
      Eigen::Map<Eigen::Matrix3Xd> out(shape_columns_.data() + 3 * num_betas_ * i, 3, num_betas_);
      out.setZero();
      for (int e = weight_begin_[i]; e < weight_begin_[i + 1]; ++e) {
        const int k = weight_joint_[e];
        const double w = weight_value_[e];
        // d/d beta of R(k)(v_posed - J(k)) + c(k)
        for (int b = 0; b < num_betas_; ++b) {
          const Eigen::Vector3d dv = m.shapedirs.block<3, 1>(3 * i, b) - rest_joint_shape_dirs_.block<3, 1>(3 * k, b);
          out.col(b) += w * (rotations_[k] * dv + joint_shape_jacobian_.block<3, 1>(3 * k, b));
        }
      }
    }
  }

  if (pose_derivatives) {
    joint_pose_jacobian_.setZero();
    for (int k = 0; k < kNumJoints; ++k)
      for (int j = k; j >= 0; j = parents[j])
        for (int d : layout_.dofs_of_joint(j)) {
          const Dof& dof = layout_.dof(d);
          joint_pose_jacobian_.block<3, 1>(3 * k, d) =
              dof.kind == DofKind::kTranslation ? dof.axis
                                                : Eigen::Vector3d(dof_rate_[d].cross(joints_.col(k) - joints_.col(j)));
        }
  }
}

void BodyEvaluator::compute_vertex_pose_jacobians(std::span<const int> vertices) {
  for (int i : vertices) {
    if (i < 0 || i >= num_vertices_) throw_invalid("vertices", "index " + std::to_string(i) + " out of range");
    compute_vertex_pose_jacobian(i);
  }
}

void BodyEvaluator::compute_vertex_pose_jacobian(int i) {
  const SmplModel& m = *model_;
  const auto& parents = m.parents;
  const bool posedirs = m.has_posedirs();
  const Eigen::Vector3d rest = v_posed_.segment<3>(3 * i);
  std::array<Eigen::Vector3d, kNumJoints> sum_below;  // sum_k w_k p_k over joints k below j
  std::array<double, kNumJoints> weight_below;
  for (int e = influence_begin_[i]; e < influence_begin_[i + 1]; ++e) {
    sum_below[influence_joint_[e]].setZero();
    weight_below[influence_joint_[e]] = 0;
  }
  Eigen::Matrix3d blended_rotation = Eigen::Matrix3d::Zero();
  for (int e = weight_begin_[i]; e < weight_begin_[i + 1]; ++e) {
    const int k = weight_joint_[e];
    const double w = weight_value_[e];
    const Eigen::Vector3d p = rotations_[k] * rest + offsets_[k];
    if (posedirs) blended_rotation += w * rotations_[k];
    for (int j = k; j >= 0; j = parents[j]) {
      sum_below[j] += w * p;
      weight_below[j] += w;
    }
  }
  double* column = pose_columns_.data() + 3 * dof_begin_[i];
  for (int e = influence_begin_[i]; e < influence_begin_[i + 1]; ++e) {
    const int j = influence_joint_[e];
    const Eigen::Vector3d lever = sum_below[j] - weight_below[j] * joints_.col(j);
    for (int d : layout_.dofs_of_joint(j)) {
      Eigen::Vector3d col;
      if (dof_is_translation_[d]) {
        col = weight_below[j] * layout_.dof(d).axis;
      } else {
        col = dof_rate_[d].cross(lever);
        if (posedirs && j > 0) {
          const Eigen::Matrix3d& dr = dof_local_rotation_derivative_[d];
          Eigen::Vector3d offset_rate = Eigen::Vector3d::Zero();
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c)
              offset_rate += m.posedirs.block<3, 1>(3 * i, 9 * (j - 1) + 3 * r + c) * dr(r, c);
          col += blended_rotation * offset_rate;
        }
      }
      Eigen::Map<Eigen::Vector3d> destination(column);
      destination = col;
      column += 3;
    }
  }
}

void BodyEvaluator::add_vertex_pose_jacobian(int i, double scale, Eigen::Ref<Eigen::Matrix3Xd> out) const {
  const auto dofs = vertex_dofs(i);
  const auto block = vertex_pose_jacobian(i);
  for (size_t c = 0; c < dofs.size(); ++c) out.col(dofs[c]) += scale * block.col(static_cast<Eigen::Index>(c));
}

void BodyEvaluator::add_vertex_pose_jacobian(int i, const Eigen::Matrix3d& m, Eigen::Ref<Eigen::Matrix3Xd> out,
                                             std::uint32_t skip_joints) const {
  // The columns come joint by joint (influence joints in order, each with its DOFs): a skipped
  // joint's columns are passed over at once.
  const double* column = pose_columns_.data() + 3 * dof_begin_[i];
  for (int e = influence_begin_[i]; e < influence_begin_[i + 1]; ++e) {
    const int j = influence_joint_[e];
    const std::vector<int>& dofs = layout_.dofs_of_joint(j);
    if ((skip_joints >> j) & 1u) {
      column += 3 * dofs.size();
      continue;
    }
    for (int d : dofs) {
      out.col(d) += m * Eigen::Map<const Eigen::Vector3d>(column);
      column += 3;
    }
  }
}

}  // namespace posefuse::body
