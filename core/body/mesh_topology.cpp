#include "body/mesh_topology.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <map>
#include <utility>

#include "common/error.hpp"

namespace posefuse::body {
namespace {

using Edge = std::pair<int, int>;  // (smaller, larger) vertex index

struct EdgeUse {
  int faces = 0;
  int forward = 0;  // uses going from the smaller to the larger index
};

std::map<Edge, EdgeUse> edge_uses(const Eigen::Matrix3Xi& faces) {
  std::map<Edge, EdgeUse> uses;
  for (Eigen::Index f = 0; f < faces.cols(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = faces(k, f), b = faces((k + 1) % 3, f);
      EdgeUse& use = uses[{std::min(a, b), std::max(a, b)}];
      ++use.faces;
      if (a < b) ++use.forward;
    }
  return uses;
}

// Number of connected fans around vertex v, given the faces incident to it.
int count_fans(int v, const std::vector<int>& incident, const Eigen::Matrix3Xi& faces) {
  // Union-find over incident faces joined when they share an edge through v.
  std::vector<int> parent(incident.size());
  for (size_t i = 0; i < parent.size(); ++i) parent[i] = static_cast<int>(i);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::map<int, int> first_face_of_other_vertex;
  for (size_t i = 0; i < incident.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const int other = faces(k, incident[i]);
      if (other == v) continue;
      auto [it, inserted] = first_face_of_other_vertex.emplace(other, static_cast<int>(i));
      if (!inserted) parent[find(static_cast<int>(i))] = find(it->second);
    }
  int fans = 0;
  for (size_t i = 0; i < parent.size(); ++i)
    if (find(static_cast<int>(i)) == static_cast<int>(i)) ++fans;
  return fans;
}

}  // namespace

MeshTopologyReport check_topology(const Eigen::Matrix3Xi& faces, int num_vertices) {
  MeshTopologyReport report;
  std::vector<std::vector<int>> incident(num_vertices);
  for (Eigen::Index f = 0; f < faces.cols(); ++f) {
    const int a = faces(0, f), b = faces(1, f), c = faces(2, f);
    if (a == b || b == c || a == c) ++report.num_degenerate_faces;
    for (int k = 0; k < 3; ++k) {
      const int idx = faces(k, f);
      if (idx < 0 || idx >= num_vertices)
        throw_invalid("faces[" + std::to_string(f) + "]", "vertex index " + std::to_string(idx) + " out of range");
      incident[idx].push_back(static_cast<int>(f));
    }
  }
  const auto uses = edge_uses(faces);
  report.num_edges = static_cast<int>(uses.size());
  for (const auto& [edge, use] : uses) {
    if (use.faces == 1) ++report.num_boundary_edges;
    if (use.faces > 2) ++report.num_nonmanifold_edges;
    if (use.faces == 2 && use.forward != 1) ++report.num_misoriented_edges;
  }
  for (int v = 0; v < num_vertices; ++v) {
    if (incident[v].empty()) {
      ++report.num_unreferenced;
      continue;
    }
    ++report.num_vertices;
    if (count_fans(v, incident[v], faces) != 1) ++report.num_nonmanifold_vertices;
  }
  report.euler_characteristic = report.num_vertices - report.num_edges + static_cast<int>(faces.cols());
  return report;
}

Eigen::Matrix3Xi face_adjacency(const Eigen::Matrix3Xi& faces, int num_vertices) {
  std::map<Edge, std::vector<std::pair<int, int>>> sides;  // edge -> (face, corner)
  for (Eigen::Index f = 0; f < faces.cols(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = faces(k, f), b = faces((k + 1) % 3, f);
      if (a < 0 || a >= num_vertices || b < 0 || b >= num_vertices)
        throw_invalid("faces[" + std::to_string(f) + "]", "vertex index out of range");
      sides[{std::min(a, b), std::max(a, b)}].emplace_back(static_cast<int>(f), k);
    }
  Eigen::Matrix3Xi adjacency = Eigen::Matrix3Xi::Constant(3, faces.cols(), -1);
  for (const auto& [edge, list] : sides) {
    if (list.size() > 2)
      throw_invalid("faces", "edge (" + std::to_string(edge.first) + ", " + std::to_string(edge.second) + ") has " +
                                 std::to_string(list.size()) + " faces; mesh is not manifold");
    if (list.size() == 2) {
      adjacency(list[0].second, list[0].first) = list[1].first;
      adjacency(list[1].second, list[1].first) = list[0].first;
    }
  }
  return adjacency;
}

double signed_volume(const Eigen::Matrix3Xd& vertices, const Eigen::Matrix3Xi& faces) {
  double six_volume = 0;
  for (Eigen::Index f = 0; f < faces.cols(); ++f)
    six_volume += vertices.col(faces(0, f)).dot(vertices.col(faces(1, f)).cross(vertices.col(faces(2, f))));
  return six_volume / 6.0;
}

}  // namespace posefuse::body
