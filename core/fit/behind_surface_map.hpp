#pragma once
// D_3D of paper 2 (II-D, Eq. 12): maps a point in K to the closest point of the volume behind
// the observed surface; a point already behind the surface maps to itself. "Behind" means: it
// projects onto a silhouette pixel with a depth reading and its z is at least that depth (the
// ray from the camera has passed the observed surface there). The paper pre-computes the map on
// a grid of 0.02 m over the capture volume; here the grid covers the point cloud's bounding box
// grown by a margin, and D_3D of a point that is not behind is the centre of the behind voxel
// nearest (Euclidean, on the grid) to the point's voxel.
//
// Computed where queried, not for the whole grid: the map keeps the frame's depth inside the
// silhouette and a min-depth pyramid of it. A query (1) walks from its voxel away from the camera
// until a behind voxel gives an upper bound R on the distance; (2) bounds the pixels onto which
// the ball of radius R can project and takes the least depth d_min there from the pyramid: every
// voxel of the ball nearer than d_min is in front of the surface there, so only the layers at
// z >= d_min can hold the answer; (3) searches shells of growing Chebyshev radius in those layers,
// classifying voxels on the fly (one projection each), until the shell radius reaches the best
// distance found. Nothing in (2) or (3) can skip a behind voxel nearer than the best, so the
// result is at exactly the grid distance a full Euclidean distance transform of the whole grid
// gives (tests/fit compare both on random frames); only which of several equally near voxels is
// returned may differ. Nothing is cached, so one map can be queried from several threads.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "fit/depth_frame.hpp"
#include "raycast/depth_camera.hpp"

namespace posefuse::fit {

class BehindSurfaceMap;

// Voxel classifications remembered between queries of one thread (float points of successive LM
// iterations lie close together). Bound to the last map it was used with and reset when used with
// another: maps are told apart by a 64-bit hash of everything a classification depends on (depth,
// grid, camera), not by address, since a new frame's map often reuses the old one's memory.
class BehindSurfaceCache {
 private:
  friend class BehindSurfaceMap;
  uint64_t map_stamp_ = 0;
  std::vector<uint8_t> state_;
};

struct BehindSurfaceParams {
  double voxel_size_m = 0.02;  // paper: 0.02 m
  // How far beyond the cloud's bounding box the grid reaches; a model point floating further
  // away is first clamped into the grid. 0.3 m covers a limb placed wrongly by a forearm length.
  double margin_m = 0.3;
  // Guard against a bounding box inflated by stray pixels: a query far from every behind voxel
  // may search the whole grid.
  int64_t max_voxels = 32'000'000;
};

class BehindSurfaceMap {
 public:
  // `camera` must outlive the map (it is kept by pointer: its ray table is large).
  // Throws posefuse::Error for a frame that does not match the camera ("frame.*"), an empty
  // silhouette ("frame.body_index"), bad params ("behind_params.*"), or a grid over max_voxels.
  BehindSurfaceMap(const DepthFrame& frame, const raycast::DepthCamera& camera, const BehindSurfaceParams& params = {});
  // The same from the frame's point cloud (build_point_cloud), when the caller has it already.
  // Throws "cloud.width" for a cloud that does not match the camera.
  BehindSurfaceMap(const PointCloud& cloud, const raycast::DepthCamera& camera, const BehindSurfaceParams& params = {});
  // The map of another cloud, as the constructor builds it, reusing this one's buffers when the
  // image size is the same (only the previous cloud's pixel box is cleared): the per-frame way,
  // without full-image allocation or clearing. Throws as the constructor; after a throw the map
  // must be rebuilt before it is queried.
  void rebuild(const PointCloud& cloud, const raycast::DepthCamera& camera, const BehindSurfaceParams& params = {});

  // Whether p_K lies behind the observed surface (exact test, no grid).
  bool is_behind(const Eigen::Vector3d& p_K) const;
  // D_3D(p_K): p_K itself when behind, otherwise the centre of the nearest behind voxel.
  // Throws posefuse::Error "p_K" for a non-finite point, "behind_surface_map" when no voxel of
  // the grid lies behind the surface.
  Eigen::Vector3d closest_behind(const Eigen::Vector3d& p_K) const;
  // The same, remembering voxel classifications in `cache` (one cache per thread): the
  // fitter's way, about 3x cheaper over an LM run.
  Eigen::Vector3d closest_behind(const Eigen::Vector3d& p_K, BehindSurfaceCache& cache) const;

  Eigen::Vector3i grid_size() const { return size_; }
  const Eigen::Vector3d& grid_origin_K() const { return origin_K_; }  // centre of voxel (0,0,0)
  double voxel_size_m() const { return voxel_size_m_; }
  // Whether voxel (i, j, k) is behind the surface: the exact test at its centre.
  bool voxel_is_behind(int i, int j, int k) const { return is_behind(voxel_centre_K(i, j, k)); }
  Eigen::Vector3d voxel_centre_K(int i, int j, int k) const {
    return origin_K_ + voxel_size_m_ * Eigen::Vector3d(i, j, k);
  }
  // Voxel whose cell holds p_K, clamped into the grid (p_K must be finite).
  Eigen::Vector3i voxel_of(const Eigen::Vector3d& p_K) const;

 private:
  const raycast::DepthCamera* camera_;
  Eigen::Vector3d search(const Eigen::Vector3d& p_K, BehindSurfaceCache* cache) const;
  // Depth (mm) of the silhouette pixel p_K projects onto; kNoDepth when none.
  uint16_t depth_at(const Eigen::Vector3d& p_K) const;
  // Layer below which no voxel of the box [lo, hi] (voxel indices) can be behind the surface.
  int first_possible_layer(const Eigen::Vector3i& lo, const Eigen::Vector3i& hi) const;

  std::vector<uint16_t> depth_mm_;  // depth inside the silhouette, kNoDepth elsewhere
  // min_depth_mm_[l]: level l of the min pyramid over 2^l x 2^l pixel blocks (kNoReading where
  // no pixel of the block has depth); level 0 is depth_mm_ with kNoReading for kNoDepth.
  std::vector<std::vector<uint16_t>> min_depth_mm_;
  std::vector<Eigen::Vector2i> level_size_;
  PixelRect box_;       // the cloud's pixel box: every reading of depth_mm_ and the pyramid lies in it (>> level)
  uint64_t stamp_ = 0;  // identifies the classification for BehindSurfaceCache
  Eigen::Vector3d origin_K_;
  Eigen::Vector3i size_;
  double voxel_size_m_ = 0;
};

}  // namespace posefuse::fit
