#pragma once
// Combinatorial checks and adjacency of triangle meshes (faces as 3 x F vertex indices).
#include <Eigen/Core>
#include <string>
#include <vector>

namespace posefuse::body {

struct MeshTopologyReport {
  int num_vertices = 0;      // vertices referenced by at least one face
  int num_unreferenced = 0;  // vertices no face uses
  int num_edges = 0;
  int num_boundary_edges = 0;        // edges with one face
  int num_nonmanifold_edges = 0;     // edges with more than two faces
  int num_misoriented_edges = 0;     // edges whose two faces traverse it in the same direction
  int num_nonmanifold_vertices = 0;  // vertices whose faces do not form one fan
  int num_degenerate_faces = 0;      // faces repeating a vertex
  int euler_characteristic = 0;      // V - E + F
  // Closed, oriented 2-manifold without degenerate faces.
  bool is_closed_manifold() const {
    return num_boundary_edges == 0 && num_nonmanifold_edges == 0 && num_misoriented_edges == 0 &&
           num_nonmanifold_vertices == 0 && num_degenerate_faces == 0 && num_unreferenced == 0;
  }
};

MeshTopologyReport check_topology(const Eigen::Matrix3Xi& faces, int num_vertices);

// For face f, neighbour(k, f) is the face across the edge from corner k to corner (k+1)%3,
// or -1 at a boundary. Requires an edge-manifold mesh (throws posefuse::Error otherwise).
Eigen::Matrix3Xi face_adjacency(const Eigen::Matrix3Xi& faces, int num_vertices);

// Signed volume enclosed by a closed mesh (positive when faces point outward).
double signed_volume(const Eigen::Matrix3Xd& vertices, const Eigen::Matrix3Xi& faces);

}  // namespace posefuse::body
