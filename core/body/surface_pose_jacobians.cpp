#include "body/surface_pose_jacobians.hpp"

#include <Eigen/Geometry>

namespace posefuse::body {

void SurfacePoseJacobians::reset(const BodySurface& surface, const BodyEvaluator& eval) {
  const int num_vertices = eval.model().num_vertices(), num_pose = eval.layout().size();
  if (model_ != &eval.model() || layout_ != &eval.layout() ||
      static_cast<int>(slot_of_vertex_.size()) != num_vertices || num_pose != num_pose_) {
    model_ = &eval.model();
    layout_ = &eval.layout();
    slot_of_vertex_.assign(static_cast<size_t>(num_vertices), -1);
    cached_vertices_.clear();
    num_pose_ = num_pose;
    // Room for every vertex up front: evaluate() never allocates after the first reset().
    store_.resize(3, 2 * static_cast<Eigen::Index>(num_pose) * num_vertices);
    find_rigid_joints(surface, eval);
    find_face_columns(surface, eval);
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

void SurfacePoseJacobians::find_face_columns(const BodySurface& surface, const BodyEvaluator& eval) {
  const PoseLayout& layout = eval.layout();
  const int num_vertices = eval.model().num_vertices();
  // Joints whose DOFs move each vertex (BodyEvaluator::vertex_dofs), then over each 1-ring: the
  // unit normal of v depends on the positions of its ring.
  std::vector<std::uint32_t> moving(static_cast<size_t>(num_vertices), 0u);
  std::vector<std::uint32_t>& ring = ring_joints_;
  ring.assign(moving.size(), 0u);
  for (int v = 0; v < num_vertices; ++v)
    for (int d : eval.vertex_dofs(v)) moving[static_cast<size_t>(v)] |= 1u << layout.dof(d).joint;
  for (int v = 0; v < num_vertices; ++v)
    for (int f : surface.faces_of_vertex(v))
      for (int k = 0; k < 3; ++k) ring[static_cast<size_t>(v)] |= moving[static_cast<size_t>(surface.faces()(k, f))];
  const Eigen::Index num_faces = surface.faces().cols();
  face_column_begin_.assign(1, 0);
  face_columns_.clear();
  for (Eigen::Index f = 0; f < num_faces; ++f) {
    std::uint32_t joints = 0;
    for (int k = 0; k < 3; ++k) joints |= ring[static_cast<size_t>(surface.faces()(k, f))];
    for (int d = 0; d < layout.size(); ++d)
      if ((joints >> layout.dof(d).joint) & 1u) face_columns_.push_back(d);
    face_column_begin_.push_back(static_cast<int>(face_columns_.size()));
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
  if (normal_needs_ring(v)) surface.vertex_normal_pose_jacobian(v, eval, store_.middleCols(begin + n, n), rigid);
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
  d_position.setZero();
  d_normal.setZero();
  write_columns(surface, eval, s, false, d_position, d_normal);
}

void SurfacePoseJacobians::evaluate_packed(const BodySurface& surface, const BodyEvaluator& eval, const SurfacePoint& s,
                                           Eigen::Ref<Eigen::Matrix3Xd> d_position,
                                           Eigen::Ref<Eigen::Matrix3Xd> d_normal) {
  write_columns(surface, eval, s, true, d_position, d_normal);
}

void SurfacePoseJacobians::write_columns(const BodySurface& surface, const BodyEvaluator& eval, const SurfacePoint& s,
                                         bool packed, Eigen::Ref<Eigen::Matrix3Xd> d_position,
                                         Eigen::Ref<Eigen::Matrix3Xd> d_normal) {
  const Eigen::Index n = num_pose_;
  const double w[3] = {s.u, s.v, 1 - s.u - s.v};
  Eigen::Index begin[3];
  for (int k = 0; k < 3; ++k) begin[k] = slot(surface, eval, surface.faces()(k, s.face));
  const Eigen::Matrix3d outer = surface.normal_projection(s);
  const std::span<const int> columns = face_columns(s.face);
  // Column by column: fixed-size arithmetic, no temporaries.
  for (size_t k = 0; k < columns.size(); ++k) {
    const Eigen::Index c = columns[k], out = packed ? static_cast<Eigen::Index>(k) : c;
    d_position.col(out) =
        w[0] * store_.col(begin[0] + c) + w[1] * store_.col(begin[1] + c) + w[2] * store_.col(begin[2] + c);
    d_normal.col(out) = outer * (w[0] * store_.col(begin[0] + n + c) + w[1] * store_.col(begin[1] + n + c) +
                                 w[2] * store_.col(begin[2] + n + c));
  }
}

}  // namespace posefuse::body
