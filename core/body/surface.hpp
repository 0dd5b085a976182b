#pragma once
// Points on the model surface (paper 2, II-C) and mesh walking (II-I).
//
// A surface point is (face, u, v) with w = 1 - u - v; its position is
//   S_p = u p0 + v p1 + w p2                        (eq. 2, p_k the face's corners in order)
// and its normal
//   S_n = Pi(u n0 + v n1 + w n2)                    (eq. 3, Pi normalises)
// with n_k the unit area-weighted vertex normals (sum of the unnormalised face normals around a
// vertex), so that the normal varies smoothly across a face and has a useful gradient in u, v.
// The same convention is used for the barycentrics of the renderer (raycast/mesh_scene.hpp).
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "body/body_evaluator.hpp"

namespace posefuse::body {

struct SurfacePoint {
  int face = 0;
  double u = 1.0 / 3, v = 1.0 / 3;
};

struct WalkResult {
  SurfacePoint end;
  int faces_crossed = 0;
  double walked_m = 0;  // length of the path on the surface
};

class BodySurface {
 public:
  // Topology only; call update() with vertex positions before any query.
  BodySurface(const Eigen::Matrix3Xi& faces, int num_vertices);

  // New vertex positions (e.g. BodyEvaluator::vertices()); recomputes the vertex normals.
  void update(const Eigen::Matrix3Xd& vertices);

  const Eigen::Matrix3Xi& faces() const { return faces_; }
  // neighbour(k, f): face across the edge from corner k to corner (k+1)%3 of f.
  const Eigen::Matrix3Xi& adjacency() const { return adjacency_; }
  const std::vector<int>& faces_of_vertex(int v) const { return faces_of_vertex_[v]; }
  const Eigen::Matrix3Xd& vertex_normals() const { return vertex_normals_; }

  Eigen::Vector3d position(const SurfacePoint& s) const;
  Eigen::Vector3d normal(const SurfacePoint& s) const;
  // d S_p / d(u, v) and d S_n / d(u, v), 3 x 2.
  Eigen::Matrix<double, 3, 2> position_uv_jacobian(const SurfacePoint& s) const;
  Eigen::Matrix<double, 3, 2> normal_uv_jacobian(const SurfacePoint& s) const;
  // d S_p / d theta and d S_n / d theta (3 x N), from the evaluator that produced the vertices
  // passed to update() (evaluated with Derivatives::kPose or more).
  void position_pose_jacobian(const SurfacePoint& s, const BodyEvaluator& eval, Eigen::Ref<Eigen::Matrix3Xd> out) const;
  void normal_pose_jacobian(const SurfacePoint& s, const BodyEvaluator& eval, Eigen::Ref<Eigen::Matrix3Xd> out) const;
  // d S_p / d beta and d S_n / d beta (3 x B, added into `out`), from an evaluator run with
  // Derivatives::kPoseAndShape (paper 2, III-B: shape and pose fitted together).
  void position_shape_jacobian(const SurfacePoint& s, const BodyEvaluator& eval,
                               Eigen::Ref<Eigen::Matrix3Xd> out) const;
  void normal_shape_jacobian(const SurfacePoint& s, const BodyEvaluator& eval, Eigen::Ref<Eigen::Matrix3Xd> out) const;
  // d n_v / d theta of the unit vertex normal n_v (3 x N, added into `out`); samples that share a
  // vertex can share this (SurfacePoseJacobians): d S_n = normal_projection(s) sum_k w_k d n_k.
  // The DOFs of the joints in the bit mask skip_joints are left out.
  void vertex_normal_pose_jacobian(int vertex, const BodyEvaluator& eval, Eigen::Ref<Eigen::Matrix3Xd> out,
                                   std::uint32_t skip_joints = 0) const;
  // d S_n / d m = (I - S_n S_n^T) / |m| at s, m = sum_k w_k n_k the unnormalised blend of eq. 3.
  Eigen::Matrix3d normal_projection(const SurfacePoint& s) const;

  // Moves s by (du, dv) in its face's barycentrics, i.e. by du (p0 - p2) + dv (p1 - p2), and
  // keeps going across edges: the remaining step is rotated about each crossed edge into the
  // next face's plane (the direction keeps its angle to the edge; Taylor et al.), until the full
  // length is walked. Stops early only at a boundary edge of an open mesh.
  WalkResult walk(const SurfacePoint& s, double du, double dv) const;

 private:
  Eigen::Vector3d corner(int face, int k) const { return vertices_.col(faces_(k, face)); }
  // d S_n = sum over the corners' 1-ring vertices q of F_q d vertex(q): calls add(q, F_q) once per
  // vertex q (the pose and shape Jacobians differ only in d vertex(q)).
  template <typename AddVertex>
  void normal_vertex_factors(const SurfacePoint& s, AddVertex&& add) const;
  // The same for the unit vertex normal n_v: d n_v = sum over v's 1-ring q of F_q d vertex(q).
  template <typename AddVertex>
  void unit_normal_factors(int vertex, AddVertex&& add) const;

  Eigen::Matrix3Xi faces_;
  Eigen::Matrix3Xi adjacency_;
  std::vector<std::vector<int>> faces_of_vertex_;
  Eigen::Matrix3Xd vertices_;
  Eigen::Matrix3Xd vertex_normal_sums_;  // unnormalised area-weighted sums
  Eigen::Matrix3Xd vertex_normals_;
};

}  // namespace posefuse::body
