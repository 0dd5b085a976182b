#pragma once
// Pose Jacobians of many surface points on one posed surface, with the per-vertex work shared.
//
// d S_p / d theta = sum_k w_k d p_k and d S_n / d theta = outer(s) sum_k w_k d n_k (surface.hpp,
// eq. 2-3) need, per corner vertex k, the Jacobian of its position and of its unit normal; the
// latter sums over k's 1-ring (about 7 vertex Jacobians). The depth samples of one frame sit
// close together, so most corners are shared by several samples: here each vertex's two
// Jacobians are computed once, dense over the N pose DOF, on first request, and reused until
// reset(). Same values as BodySurface::position_pose_jacobian / normal_pose_jacobian up to
// rounding (summation order).
//
// Rigid DOFs (analytic shortcut): a rotational DOF of joint j turns every vertex that is skinned
// only to joints at or below j about the posed joint c(j), d q = W_d x (q - c(j)). When all of
// v's 1-ring moves so, its area-weighted normal turns with it and d n_v = W_d x n_v (the sum over
// the ring's edges cancels the lever), and a translation leaves n_v unchanged: the 1-ring sum is
// needed only for the DOFs of joints at the skinning seams. Off for models with pose correctives
// (they deform the ring under every joint's rotation).
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "body/body_evaluator.hpp"
#include "body/surface.hpp"

namespace posefuse::body {

class SurfacePoseJacobians {
 public:
  // Forgets every cached vertex: call whenever the evaluator or the surface changed.
  void reset(const BodySurface& surface, const BodyEvaluator& eval);

  // d S_p / d theta and d S_n / d theta at s (3 x N each, overwritten). `eval` (evaluated with
  // Derivatives::kPose or more) produced the vertices of `surface`; both unchanged since reset().
  void evaluate(const BodySurface& surface, const BodyEvaluator& eval, const SurfacePoint& s,
                Eigen::Ref<Eigen::Matrix3Xd> d_position, Eigen::Ref<Eigen::Matrix3Xd> d_normal);

 private:
  // Column offset of vertex v's [d p_v, d n_v] (3 x 2N) in store_, computed on first use.
  Eigen::Index slot(const BodySurface& surface, const BodyEvaluator& eval, int v);

  // Per vertex, bit j set: every vertex of its 1-ring is skinned only to joints at or below j.
  void find_rigid_joints(const BodySurface& surface, const BodyEvaluator& eval);

  const SmplModel* model_ = nullptr;
  int num_pose_ = 0;
  std::vector<std::uint32_t> rigid_joints_;
  std::vector<int> slot_of_vertex_;  // -1: not computed since reset()
  std::vector<int> cached_vertices_;
  Eigen::Matrix3Xd store_;           // 3 x (2N * number of vertices), filled in order of first use
};

}  // namespace posefuse::body
