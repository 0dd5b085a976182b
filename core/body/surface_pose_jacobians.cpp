#include "body/surface_pose_jacobians.hpp"

namespace posefuse::body {

void SurfacePoseJacobians::reset(int num_vertices, int num_pose) {
  if (static_cast<int>(slot_of_vertex_.size()) != num_vertices || num_pose != num_pose_) {
    slot_of_vertex_.assign(static_cast<size_t>(num_vertices), -1);
    cached_vertices_.clear();
    num_pose_ = num_pose;
    // Room for every vertex up front: evaluate() never allocates after the first reset().
    store_.resize(3, 2 * static_cast<Eigen::Index>(num_pose) * num_vertices);
    return;
  }
  for (int v : cached_vertices_) slot_of_vertex_[static_cast<size_t>(v)] = -1;
  cached_vertices_.clear();
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
  surface.vertex_normal_pose_jacobian(v, eval, store_.middleCols(begin + n, n));
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
