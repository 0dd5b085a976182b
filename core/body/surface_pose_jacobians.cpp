#include "body/surface_pose_jacobians.hpp"

#include <Eigen/Geometry>

namespace posefuse::body {

void SurfacePoseJacobians::reset(const BodySurface& surface, const BodyEvaluator& eval) {
  const int num_vertices = eval.model().num_vertices(), num_pose = eval.layout().size();
  if (model_ != &eval.model() || static_cast<int>(slot_of_vertex_.size()) != num_vertices || num_pose != num_pose_) {
    model_ = &eval.model();
    slot_of_vertex_.assign(static_cast<size_t>(num_vertices), -1);
    cached_vertices_.clear();
    num_pose_ = num_pose;
    // Room for every vertex up front: evaluate() never allocates after the first reset().
    store_.resize(3, 2 * static_cast<Eigen::Index>(num_pose) * num_vertices);
    find_rigid_joints(surface, eval);
    return;
  }
  for (int v : cached_vertices_) slot_of_vertex_[static_cast<size_t>(v)] = -1;
  cached_vertices_.clear();
}

void SurfacePoseJacobians::find_rigid_joints(const BodySurface& surface, const BodyEvaluator& eval) {
  const SmplModel& m = eval.model();
  const int num_vertices = m.num_vertices();
  rigid_joints_.assign(static_cast<size_t>(num_vertices), 0u);
  if (m.has_posedirs()) return;
  // Joints at or above each skinning joint k (k and its ancestors): those whose rotation moves
  // k's vertices rigidly. A vertex moves rigidly under the joints above all its skinning joints.
  std::vector<std::uint32_t> rigid_of_vertex(static_cast<size_t>(num_vertices), ~0u);
  for (int i = 0; i < num_vertices; ++i)
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(m.weights, i); it; ++it) {
      if (it.value() == 0.0) continue;
      std::uint32_t above = 0;
      for (int j = static_cast<int>(it.col()); j >= 0; j = m.parents[j]) above |= 1u << j;
      rigid_of_vertex[static_cast<size_t>(i)] &= above;
    }
  for (int v = 0; v < num_vertices; ++v) {
    std::uint32_t rigid = rigid_of_vertex[static_cast<size_t>(v)];
    for (int f : surface.faces_of_vertex(v))
      for (int k = 0; k < 3; ++k) rigid &= rigid_of_vertex[static_cast<size_t>(surface.faces()(k, f))];
    rigid_joints_[static_cast<size_t>(v)] = rigid;
  }
}

Eigen::Index SurfacePoseJacobians::slot(const BodySurface& surface, const BodyEvaluator& eval, int v) {
  int& slot = slot_of_vertex_[static_cast<size_t>(v)];
  const Eigen::Index n = num_pose_;
  if (slot >= 0) return 2 * n * slot;
  slot = static_cast<int>(cached_vertices_.size());
  cached_vertices_.push_back(v);
  const Eigen::Index begin = 2 * n * slot;
  store_.middleCols(begin, 2 * n).setZero();
  eval.add_vertex_pose_jacobian(v, 1.0, store_.middleCols(begin, n));
  const std::uint32_t rigid = rigid_joints_[static_cast<size_t>(v)];
  surface.vertex_normal_pose_jacobian(v, eval, store_.middleCols(begin + n, n), rigid);
  const Eigen::Vector3d normal = surface.vertex_normals().col(v);
  for (int d : eval.vertex_dofs(v)) {
    const Dof& dof = eval.layout().dof(d);
    if (((rigid >> dof.joint) & 1u) && dof.kind == DofKind::kRotation)
      store_.col(begin + n + d) = eval.dof_rate(d).cross(normal);
  }
  return begin;
}

void SurfacePoseJacobians::evaluate(const BodySurface& surface, const BodyEvaluator& eval, const SurfacePoint& s,
                                    Eigen::Ref<Eigen::Matrix3Xd> d_position, Eigen::Ref<Eigen::Matrix3Xd> d_normal) {
  const Eigen::Index n = num_pose_;
  const double w[3] = {s.u, s.v, 1 - s.u - s.v};
  Eigen::Index begin[3];
  for (int k = 0; k < 3; ++k) begin[k] = slot(surface, eval, surface.faces()(k, s.face));
  const Eigen::Matrix3d outer = surface.normal_projection(s);
  // Column by column: fixed-size arithmetic, no temporaries.
  for (Eigen::Index c = 0; c < n; ++c) {
    d_position.col(c) = w[0] * store_.col(begin[0] + c) + w[1] * store_.col(begin[1] + c) + w[2] * store_.col(begin[2] + c);
    d_normal.col(c) = outer * (w[0] * store_.col(begin[0] + n + c) + w[1] * store_.col(begin[1] + n + c) +
                               w[2] * store_.col(begin[2] + n + c));
  }
}

}  // namespace posefuse::body
