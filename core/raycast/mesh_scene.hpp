#pragma once
// An Embree scene holding one triangle mesh (e.g. one posed body model) in the camera frame K.
//
// The topology is fixed at construction; every pose only rewrites the vertex buffer and refits
// the BVH (RTC_BUILD_QUALITY_REFIT), which is much cheaper than a rebuild. Queries:
//  - render(): z-depth in mm (uint16, as the camera), body index, face id and barycentrics per
//    pixel, with 8-wide ray packets, only inside the mesh's projected bounding box;
//  - visible(): whether the straight line from the camera centre to each point is free;
//  - closest_point(): nearest surface point to any 3-D point (rtcPointQuery).
// Barycentrics follow core/body's surface convention (paper 2, eq. 2): a point (face, u, v) is
// u * corner0 + v * corner1 + (1 - u - v) * corner2 of the face.
// Not thread-safe: one scene per worker.
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "raycast/depth_camera.hpp"
#include "raycast/embree_device.hpp"

namespace posefuse::raycast {

inline constexpr uint8_t kNoBody = 255;  // Kinect body index for "no body"

struct RenderImages {
  int width = 0, height = 0;
  std::vector<uint16_t> depth_mm;   // z in mm, 0 = no hit (also beyond 65.535 m)
  std::vector<uint8_t> body_index;  // body_index where hit, kNoBody elsewhere
  std::vector<int32_t> face;        // face id, -1 where nothing was hit
  std::vector<float> u, v;          // barycentrics of the hit (see the header comment)
  // The smallest pixel rectangle [begin, end) holding every hit (empty: none); render() sets it.
  int hit_col_begin = 0, hit_col_end = 0, hit_row_begin = 0, hit_row_end = 0;
  void resize(int w, int h);  // and clears: no hits
};

struct ClosestPoint {
  int face = -1;
  double u = 0, v = 0;    // barycentrics as above
  Eigen::Vector3d point;  // on the surface, in K
  double distance = 0;    // metres
};

class MeshScene {
 public:
  // faces: 3 x F vertex indices; vertices are set with update_vertices before any query.
  MeshScene(std::shared_ptr<EmbreeDevice> device, const Eigen::Matrix3Xi& faces, int num_vertices);
  ~MeshScene();
  MeshScene(const MeshScene&) = delete;
  MeshScene& operator=(const MeshScene&) = delete;

  // New vertex positions in K (metres), 3 x V; refits the BVH.
  void update_vertices(const Eigen::Matrix3Xd& vertices_K);

  // Renders into `out` (resized to the camera). Only the depth and body index buffers are
  // needed by the simulator; the face and barycentric buffers serve the fitter.
  void render(const DepthCamera& camera, uint8_t body_index, RenderImages& out) const;

  // For each point in K: true when the segment from the camera centre to it is free of the
  // mesh up to `tolerance_m` before the point (so a point on the surface sees itself).
  std::vector<bool> visible(const Eigen::Matrix3Xd& points_K, double tolerance_m = 0.002) const;

  // First hit of the ray from the camera centre through each point (any distance along the ray):
  // face, barycentrics, hit point and ray length; face = -1 where the ray misses. The fitter uses
  // it at its depth samples as a render of the model restricted to those pixels (paper 2, II-J).
  void first_hits(const std::vector<Eigen::Vector3d>& through_K, std::vector<ClosestPoint>& hits) const;

  // Nearest point of the mesh surface to p (throws if no vertices were set).
  ClosestPoint closest_point(const Eigen::Vector3d& p_K) const;

  const Eigen::Matrix3Xi& faces() const { return faces_; }
  int num_vertices() const { return num_vertices_; }

 private:
  std::shared_ptr<EmbreeDevice> device_;
  RTCScene scene_ = nullptr;
  RTCGeometry geometry_ = nullptr;
  Eigen::Matrix3Xi faces_;
  int num_vertices_ = 0;
  float* vertex_buffer_ = nullptr;  // owned by Embree
  bool has_vertices_ = false;
  Eigen::Vector3d box_min_, box_max_;  // bounding box of the current vertices
};

}  // namespace posefuse::raycast
