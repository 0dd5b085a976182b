#pragma once
// Everything the per-frame fit (FrameFitter) reads from one frame (paper 2, II-A, II-D, II-H):
// the N_s depth samples with their normals, D_2D, D_3D and the forearm directions from the
// wrist IMUs. prepare_observation() builds it from a depth frame and its camera skeleton with
// the preprocessing of fit/ (depth_frame, zone_sampling, point_normals, silhouette_distance,
// behind_surface_map).
#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "fit/behind_surface_map.hpp"
#include "fit/depth_frame.hpp"
#include "fit/fit_options.hpp"
#include "fit/silhouette_distance.hpp"
#include "fit/zone_sampling.hpp"
#include "raycast/depth_camera.hpp"

namespace posefuse::fit {

// Forearm pointing directions E_left, E_right of eq. 9 in K (unit, elbow -> wrist), from the
// wrist IMU orientations; absent when that IMU has no orientation for the frame. Each direction's
// imu term is weighted by lambda_imu times its weight (forearm_direction_weight).
struct ForearmDirections {
  std::optional<Eigen::Vector3d> left_K, right_K;
  double left_weight = 1.0, right_weight = 1.0;
};

// The imu term's weight for a forearm direction of predicted RMS error axis_rms_rad: 1 where the
// direction is confident (its Rayleigh 99 % bound within 15 degrees, u <= 7.0 degrees), and
// inverse to its variance beyond, (7.0 degrees / u)^2, so that an axis known less well still keeps
// a hidden forearm out of directions far from it while pulling a seen one little. NaN gives 0.
double forearm_direction_weight(double axis_rms_rad);

struct FrameObservation {
  std::vector<Eigen::Vector3d> points_K;   // p_i, metres
  std::vector<Eigen::Vector3d> normals_K;  // n_i, unit, towards the camera
  SilhouetteDistanceMap silhouette;        // D_2D
  std::optional<BehindSurfaceMap> behind;  // D_3D (always set by prepare_observation)
  ForearmDirections forearm;
};

// Throws posefuse::Error naming the field: no samples ("observation.points_K"), sizes that differ
// ("observation.normals_K"), a non-finite or non-unit value ("observation.points_K[i]", ...), a
// missing D_3D ("observation.behind"), an empty D_2D ("observation.silhouette"), a forearm
// direction that is not a unit vector ("observation.forearm.left_K").
void validate(const FrameObservation& observation);

// Thread CPU seconds of each part of prepare_observation (for the per-phase benchmark tables).
struct ObservationTimes {
  double cloud_s = 0;     // point cloud
  double sampling_s = 0;  // zone sampling (zones, edge band, draw)
  double normals_s = 0;   // PCA normals of the samples
  double d2d_s = 0;       // D_2D
  double d3d_s = 0;       // D_3D map construction (queries happen in the fit)
  double total_s() const { return cloud_s + sampling_s + normals_s + d2d_s + d3d_s; }
};

// II-H preprocessing: point cloud, zone sampling of options.num_samples pixels by the camera
// skeleton, PCA normals (samples without a normal are dropped), D_2D, D_3D. Throws
// posefuse::Error for a frame that does not match the camera ("frame.*"), an empty silhouette
// or one without depth readings ("frame.body_index"), a missing skeleton ("skeleton"), a
// non-finite joint ("skeleton[i]"), or too few samples with a normal ("frame.depth_mm").
FrameObservation prepare_observation(const DepthFrame& frame, const raycast::DepthCamera& camera,
                                     const std::optional<KinectSkeleton>& skeleton_K, const FitOptions& options,
                                     const ForearmDirections& forearm = {}, ObservationTimes* times = nullptr);

// What prepare_observation keeps from one frame to the next so that a frame allocates and clears
// no full-image buffer: the last observation (D_2D and D_3D are full-image maps) and the point
// cloud, each cleared only over the region the last frame used. One per tracker (or thread).
struct ObservationBuffers {
  FrameObservation observation;
  PointCloud cloud;
  std::vector<uint8_t> silhouette;
};

// The same observation as prepare_observation, built in buffers.observation (returned) over the
// buffers of the previous frame; errors as prepare_observation. After a throw the buffers stay
// usable for the next frame, but buffers.observation must not be used.
const FrameObservation& prepare_observation(ObservationBuffers& buffers, const DepthFrame& frame,
                                            const raycast::DepthCamera& camera,
                                            const std::optional<KinectSkeleton>& skeleton_K, const FitOptions& options,
                                            const ForearmDirections& forearm = {}, ObservationTimes* times = nullptr);

}  // namespace posefuse::fit
