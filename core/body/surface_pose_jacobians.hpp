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
//
// Sparsity: a surface point on face f moves only with the DOFs of the joints that skin some
// vertex of its corners' 1-rings (and their ancestors); face_columns(f) lists them, ascending,
// and evaluate_packed() writes only those columns, so that the normal equations need not scan
// the N columns for zeros.
#include <Eigen/Core>
#include <cstdint>
#include <span>
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
  // The same over the columns face_columns(s.face) only: column c of d_position / d_normal (3 x m,
  // m = face_columns(s.face).size()) is the derivative by DOF face_columns(s.face)[c]. Every
  // other column of the dense Jacobian is zero.
  void evaluate_packed(const BodySurface& surface, const BodyEvaluator& eval, const SurfacePoint& s,
                       Eigen::Ref<Eigen::Matrix3Xd> d_position, Eigen::Ref<Eigen::Matrix3Xd> d_normal);
  // Whether d n_v needs the pose Jacobians of v's 1-ring (valid after reset()): false when every
  // joint that moves the ring turns it rigidly, so that the shortcut above gives all of d n_v and
  // only v's own Jacobian is read (BodyEvaluator::kPoseOnRequest callers may skip the ring).
  bool normal_needs_ring(int v) const {
    return (ring_joints_[static_cast<size_t>(v)] & ~rigid_joints_[static_cast<size_t>(v)]) != 0;
  }
  // The DOFs that can move a point of face f or turn its normal, ascending (valid after reset()).
  std::span<const int> face_columns(int face) const {
    return {face_columns_.data() + face_column_begin_[static_cast<size_t>(face)],
            static_cast<size_t>(face_column_begin_[static_cast<size_t>(face) + 1] -
                                face_column_begin_[static_cast<size_t>(face)])};
  }

 private:
  // Column offset of vertex v's [d p_v, d n_v] (3 x 2N) in store_, computed on first use.
  Eigen::Index slot(const BodySurface& surface, const BodyEvaluator& eval, int v);

  // Per vertex, bit j set: every vertex of its 1-ring is skinned only to joints at or below j.
  void find_rigid_joints(const BodySurface& surface, const BodyEvaluator& eval);
  // face_columns() of every face.
  void find_face_columns(const BodySurface& surface, const BodyEvaluator& eval);
  // The columns face_columns(s.face) of both Jacobians, into column k of the list (packed) or
  // into the DOF's own column.
  void write_columns(const BodySurface& surface, const BodyEvaluator& eval, const SurfacePoint& s, bool packed,
                     Eigen::Ref<Eigen::Matrix3Xd> d_position, Eigen::Ref<Eigen::Matrix3Xd> d_normal);

  const SmplModel* model_ = nullptr;
  const PoseLayout* layout_ = nullptr;
  int num_pose_ = 0;
  std::vector<int> face_column_begin_, face_columns_;
  std::vector<std::uint32_t> rigid_joints_;
  std::vector<std::uint32_t> ring_joints_;  // per vertex, bit j: joint j's DOFs move some vertex of its 1-ring
  std::vector<int> slot_of_vertex_;         // -1: not computed since reset()
  std::vector<int> cached_vertices_;
  Eigen::Matrix3Xd store_;  // 3 x (2N * number of vertices), filled in order of first use
};

}  // namespace posefuse::body
