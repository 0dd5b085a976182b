#pragma once
// D_3D of paper 2 (II-D, Eq. 12): maps a point in K to the closest point of the volume behind
// the observed surface; a point already behind the surface maps to itself. "Behind" means: it
// projects onto a silhouette pixel with a depth reading and its z is at least that depth (the
// ray from the camera has passed the observed surface there). The paper pre-computes the map on
// a grid of 0.02 m over the capture volume; here the grid covers the point cloud's bounding box
// grown by a margin, and the nearest behind-voxel of every voxel comes from an exact squared
// Euclidean distance transform (Felzenszwalb-Huttenlocher, separable) that carries the argmin.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "fit/depth_frame.hpp"
#include "raycast/depth_camera.hpp"

namespace posefuse::fit {

struct BehindSurfaceParams {
  double voxel_size_m = 0.02;  // paper: 0.02 m
  // How far beyond the cloud's bounding box the grid reaches; a model point floating further
  // away is first clamped into the grid. 0.3 m covers a limb placed wrongly by a forearm length.
  double margin_m = 0.3;
  int64_t max_voxels = 32'000'000;  // guard against a bounding box inflated by stray pixels
};

class BehindSurfaceMap {
 public:
  // `camera` must outlive the map (it is kept by pointer: its ray table is large).
  // Throws posefuse::Error for a frame that does not match the camera ("frame.*"), an empty
  // silhouette ("frame.body_index"), bad params ("behind_params.*"), or a grid over max_voxels.
  BehindSurfaceMap(const DepthFrame& frame, const raycast::DepthCamera& camera, const BehindSurfaceParams& params = {});

  // Whether p_K lies behind the observed surface (exact test, no grid).
  bool is_behind(const Eigen::Vector3d& p_K) const;
  // D_3D(p_K): p_K itself when behind, otherwise the centre of the nearest behind voxel.
  Eigen::Vector3d closest_behind(const Eigen::Vector3d& p_K) const;

  Eigen::Vector3i grid_size() const { return size_; }
  const Eigen::Vector3d& grid_origin_K() const { return origin_K_; }  // centre of voxel (0,0,0)
  double voxel_size_m() const { return voxel_size_m_; }
  // Whether voxel (i, j, k) is behind the surface (for tests and debugging).
  bool voxel_is_behind(int i, int j, int k) const { return voxel_behind_[index(i, j, k)] != 0; }
  Eigen::Vector3d voxel_centre_K(int i, int j, int k) const {
    return origin_K_ + voxel_size_m_ * Eigen::Vector3d(i, j, k);
  }

 private:
  size_t index(int i, int j, int k) const { return (static_cast<size_t>(k) * size_.y() + j) * size_.x() + i; }

  const raycast::DepthCamera* camera_;
  std::vector<uint16_t> depth_mm_;     // depth inside the silhouette, kNoDepth elsewhere
  Eigen::Vector3d origin_K_;
  Eigen::Vector3i size_;
  double voxel_size_m_;
  std::vector<uint8_t> voxel_behind_;
  std::vector<int32_t> nearest_behind_;  // voxel index of the nearest behind voxel, -1 if none
};

}  // namespace posefuse::fit
