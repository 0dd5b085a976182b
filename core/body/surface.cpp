#include "body/surface.hpp"

#include <Eigen/Geometry>
#include <array>
#include <cmath>

#include "body/mesh_topology.hpp"
#include "common/error.hpp"

namespace posefuse::body {
namespace {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

Eigen::Vector3d weights_of(const SurfacePoint& s) { return {s.u, s.v, 1 - s.u - s.v}; }

}  // namespace

BodySurface::BodySurface(const Eigen::Matrix3Xi& faces, int num_vertices)
    : faces_(faces), adjacency_(face_adjacency(faces, num_vertices)), faces_of_vertex_(num_vertices) {
  for (Eigen::Index f = 0; f < faces.cols(); ++f)
    for (int k = 0; k < 3; ++k) faces_of_vertex_[faces(k, f)].push_back(static_cast<int>(f));
}

void BodySurface::update(const Eigen::Matrix3Xd& vertices) {
  if (vertices.cols() != static_cast<Eigen::Index>(faces_of_vertex_.size()))
    throw_invalid("vertices", std::to_string(vertices.cols()) + " vertices, surface has " +
                                  std::to_string(faces_of_vertex_.size()));
  vertices_ = vertices;
  vertex_normal_sums_.setZero(3, vertices.cols());
  for (Eigen::Index f = 0; f < faces_.cols(); ++f) {
    const Eigen::Vector3d a = corner(static_cast<int>(f), 0), b = corner(static_cast<int>(f), 1),
                          c = corner(static_cast<int>(f), 2);
    const Eigen::Vector3d area_normal = (b - a).cross(c - a);  // length = 2 * area
    for (int k = 0; k < 3; ++k) vertex_normal_sums_.col(faces_(k, f)) += area_normal;
  }
  vertex_normals_ = vertex_normal_sums_.colwise().normalized();
}

Eigen::Vector3d BodySurface::position(const SurfacePoint& s) const {
  const Eigen::Vector3d w = weights_of(s);
  return w[0] * corner(s.face, 0) + w[1] * corner(s.face, 1) + w[2] * corner(s.face, 2);
}

Eigen::Vector3d BodySurface::normal(const SurfacePoint& s) const {
  const Eigen::Vector3d w = weights_of(s);
  Eigen::Vector3d m = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) m += w[k] * vertex_normals_.col(faces_(k, s.face));
  return m.normalized();
}

Eigen::Matrix<double, 3, 2> BodySurface::position_uv_jacobian(const SurfacePoint& s) const {
  Eigen::Matrix<double, 3, 2> j;
  j.col(0) = corner(s.face, 0) - corner(s.face, 2);
  j.col(1) = corner(s.face, 1) - corner(s.face, 2);
  return j;
}

Eigen::Matrix<double, 3, 2> BodySurface::normal_uv_jacobian(const SurfacePoint& s) const {
  const Eigen::Vector3d n0 = vertex_normals_.col(faces_(0, s.face)), n1 = vertex_normals_.col(faces_(1, s.face)),
                        n2 = vertex_normals_.col(faces_(2, s.face));
  const Eigen::Matrix3d project = normal_projection(s);
  Eigen::Matrix<double, 3, 2> j;
  j.col(0) = project * (n0 - n2);
  j.col(1) = project * (n1 - n2);
  return j;
}

void BodySurface::position_pose_jacobian(const SurfacePoint& s, const BodyEvaluator& eval,
                                         Eigen::Ref<Eigen::Matrix3Xd> out) const {
  const Eigen::Vector3d w = weights_of(s);
  for (int k = 0; k < 3; ++k) eval.add_vertex_pose_jacobian(faces_(k, s.face), w[k], out);
}

void BodySurface::position_shape_jacobian(const SurfacePoint& s, const BodyEvaluator& eval,
                                          Eigen::Ref<Eigen::Matrix3Xd> out) const {
  const Eigen::Vector3d w = weights_of(s);
  for (int k = 0; k < 3; ++k) out += w[k] * eval.vertex_shape_jacobian(faces_(k, s.face));
}

template <typename AddVertex>
void BodySurface::unit_normal_factors(int vertex, AddVertex&& add) const {
  // n = N / |N|, N = sum over the vertex's faces (b - a) x (c - a), so
  // d N = sum over faces ([c - b]x J_a + [a - c]x J_b + [b - a]x J_c). The cross-product factors
  // are linear in the edge, so each 1-ring vertex's edges are summed first: one 3 x 3 factor
  // P [e_q]x per ring vertex q, P = (I - n n^T) / |N|.
  constexpr int kMaxRing = 32;
  std::array<int, kMaxRing> ring_vertex;
  std::array<Eigen::Vector3d, kMaxRing> ring_edge;
  int ring_size = 0;
  const Eigen::Vector3d n = vertex_normals_.col(vertex);
  const Eigen::Matrix3d project =
      (Eigen::Matrix3d::Identity() - n * n.transpose()) / vertex_normal_sums_.col(vertex).norm();
  const auto accumulate = [&](int q, const Eigen::Vector3d& edge) {
    for (int r = 0; r < ring_size; ++r)
      if (ring_vertex[r] == q) {
        ring_edge[r] += edge;
        return;
      }
    if (ring_size == kMaxRing) {  // an unusually high valence: flush into the output directly
      add(q, Eigen::Matrix3d(project * skew(edge)));
      return;
    }
    ring_vertex[ring_size] = q;
    ring_edge[ring_size++] = edge;
  };
  for (int f : faces_of_vertex_[vertex]) {
    const Eigen::Vector3d a = corner(f, 0), b = corner(f, 1), c = corner(f, 2);
    accumulate(faces_(0, f), c - b);
    accumulate(faces_(1, f), a - c);
    accumulate(faces_(2, f), b - a);
  }
  for (int r = 0; r < ring_size; ++r) add(ring_vertex[r], Eigen::Matrix3d(project * skew(ring_edge[r])));
}

Eigen::Matrix3d BodySurface::normal_projection(const SurfacePoint& s) const {
  const Eigen::Vector3d w = weights_of(s);
  Eigen::Vector3d m = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) m += w[k] * vertex_normals_.col(faces_(k, s.face));
  const Eigen::Vector3d unit = m.normalized();
  return (Eigen::Matrix3d::Identity() - unit * unit.transpose()) / m.norm();
}

template <typename AddVertex>
void BodySurface::normal_vertex_factors(const SurfacePoint& s, AddVertex&& add) const {
  // S_n = Pi(m), m = sum_k w_k n_k: d S_n = outer sum_k w_k d n_k, outer = (I - S_n S_n^T) / |m|.
  // The 3 x 3 factors are summed per vertex first, so that each vertex of the corners' 1-rings
  // costs one product with its Jacobian (about 12 instead of 21).
  const Eigen::Vector3d w = weights_of(s);
  const Eigen::Matrix3d outer = normal_projection(s);
  constexpr int kMaxRing = 96;
  std::array<int, kMaxRing> ring_vertex;
  std::array<Eigen::Matrix3d, kMaxRing> ring_factor;
  int ring_size = 0;
  const auto accumulate = [&](int vertex, const Eigen::Matrix3d& factor) {
    for (int r = 0; r < ring_size; ++r)
      if (ring_vertex[r] == vertex) {
        ring_factor[r] += factor;
        return;
      }
    if (ring_size == kMaxRing) {  // an unusually high valence: flush into the output directly
      add(vertex, factor);
      return;
    }
    ring_vertex[ring_size] = vertex;
    ring_factor[ring_size++] = factor;
  };
  for (int k = 0; k < 3; ++k) {
    const Eigen::Matrix3d chain = w[k] * outer;
    unit_normal_factors(faces_(k, s.face),
                        [&](int q, const Eigen::Matrix3d& factor) { accumulate(q, chain * factor); });
  }
  for (int r = 0; r < ring_size; ++r) add(ring_vertex[r], ring_factor[r]);
}

void BodySurface::vertex_normal_pose_jacobian(int vertex, const BodyEvaluator& eval, Eigen::Ref<Eigen::Matrix3Xd> out,
                                              std::uint32_t skip_joints) const {
  unit_normal_factors(vertex, [&](int q, const Eigen::Matrix3d& factor) {
    eval.add_vertex_pose_jacobian(q, factor, out, skip_joints);
  });
}

void BodySurface::normal_pose_jacobian(const SurfacePoint& s, const BodyEvaluator& eval,
                                       Eigen::Ref<Eigen::Matrix3Xd> out) const {
  normal_vertex_factors(
      s, [&](int vertex, const Eigen::Matrix3d& factor) { eval.add_vertex_pose_jacobian(vertex, factor, out); });
}

void BodySurface::normal_shape_jacobian(const SurfacePoint& s, const BodyEvaluator& eval,
                                        Eigen::Ref<Eigen::Matrix3Xd> out) const {
  normal_vertex_factors(s, [&](int vertex, const Eigen::Matrix3d& factor) {
    out.noalias() += factor * eval.vertex_shape_jacobian(vertex);
  });
}

WalkResult BodySurface::walk(const SurfacePoint& start, double du, double dv) const {
  WalkResult result;
  int face = start.face;
  Eigen::Vector3d bary = weights_of(start);
  Eigen::Vector3d step = du * (corner(face, 0) - corner(face, 2)) + dv * (corner(face, 1) - corner(face, 2));
  constexpr int kMaxCrossings = 100000;
  for (int crossing = 0; crossing < kMaxCrossings; ++crossing) {
    // Barycentric change of the whole remaining step within this face.
    const Eigen::Vector3d e0 = corner(face, 0) - corner(face, 2), e1 = corner(face, 1) - corner(face, 2);
    Eigen::Matrix2d gram;
    gram << e0.dot(e0), e0.dot(e1), e0.dot(e1), e1.dot(e1);
    const Eigen::Vector2d ab = gram.ldlt().solve(Eigen::Vector2d(e0.dot(step), e1.dot(step)));
    const Eigen::Vector3d delta(ab[0], ab[1], -ab[0] - ab[1]);
    double t_exit = 1.0;
    int exit_corner = -1;
    for (int k = 0; k < 3; ++k)
      if (delta[k] < 0) {
        const double t = std::max(0.0, -bary[k] / delta[k]);
        if (t < t_exit) {
          t_exit = t;
          exit_corner = k;
        }
      }
    const double length = step.norm();
    if (exit_corner < 0) {
      bary += delta;
      result.walked_m += length;
      break;
    }
    bary += t_exit * delta;
    bary[exit_corner] = 0;
    result.walked_m += t_exit * length;
    step *= 1 - t_exit;
    const int edge = (exit_corner + 1) % 3;  // edge from corner `edge` to corner `edge + 1`
    const int next = adjacency_(edge, face);
    if (next < 0) break;  // open boundary
    const int va = faces_(edge, face), vb = faces_((edge + 1) % 3, face);
    const double ba = bary[edge], bb = bary[(edge + 1) % 3];
    // Unfold: rotate the remaining step about the shared edge from this face's plane into the next.
    const Eigen::Vector3d axis = (vertices_.col(vb) - vertices_.col(va)).normalized();
    const Eigen::Vector3d n_from =
        (corner(face, 1) - corner(face, 0)).cross(corner(face, 2) - corner(face, 0)).normalized();
    const Eigen::Vector3d n_to =
        (corner(next, 1) - corner(next, 0)).cross(corner(next, 2) - corner(next, 0)).normalized();
    const double angle = std::atan2(n_from.cross(n_to).dot(axis), n_from.dot(n_to));
    step = Eigen::AngleAxisd(angle, axis) * step;
    Eigen::Vector3d next_bary = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      if (faces_(k, next) == va) next_bary[k] = ba;
      if (faces_(k, next) == vb) next_bary[k] = bb;
    }
    bary = next_bary;
    face = next;
    ++result.faces_crossed;
  }
  result.end = {face, bary[0], bary[1]};
  return result;
}

}  // namespace posefuse::body
