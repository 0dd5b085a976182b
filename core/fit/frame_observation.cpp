#include "fit/frame_observation.hpp"

#include <cmath>
#include <string>
#include <utility>

#include "common/error.hpp"
#include "common/thread_cpu_time.hpp"
#include "fit/point_normals.hpp"
#include "forearm/orientation_uncertainty.hpp"

namespace posefuse::fit {
namespace {

// Fewer samples than this cannot constrain 40 DOF.
constexpr size_t kMinSamples = 10;

void check_unit(const std::optional<Eigen::Vector3d>& v, const char* field) {
  if (v && (!v->allFinite() || std::abs(v->norm() - 1) > 1e-3)) throw_invalid(field, "must be a finite unit vector");
}

}  // namespace

void validate(const FrameObservation& o) {
  if (o.points_K.empty()) throw_precondition("observation.points_K", "no depth samples");
  if (o.normals_K.size() != o.points_K.size())
    throw_invalid("observation.normals_K",
                  std::to_string(o.normals_K.size()) + " normals for " + std::to_string(o.points_K.size()) + " points");
  for (size_t i = 0; i < o.points_K.size(); ++i) {
    if (!o.points_K[i].allFinite() || o.points_K[i].z() <= 0)
      throw_invalid("observation.points_K[" + std::to_string(i) + "]", "not finite or not in front of the camera");
    if (!o.normals_K[i].allFinite() || std::abs(o.normals_K[i].norm() - 1) > 1e-3)
      throw_invalid("observation.normals_K[" + std::to_string(i) + "]", "not a finite unit vector");
  }
  if (o.silhouette.width <= 0 || o.silhouette.height <= 0 ||
      o.silhouette.closest_pixel.size() != static_cast<size_t>(o.silhouette.width) * o.silhouette.height)
    throw_invalid("observation.silhouette", "empty or inconsistent D_2D map");
  if (!o.behind) throw_invalid("observation.behind", "D_3D map missing");
  check_unit(o.forearm.left_K, "observation.forearm.left_K");
  check_unit(o.forearm.right_K, "observation.forearm.right_K");
  for (const auto& [weight, field] : {std::pair{o.forearm.left_weight, "observation.forearm.left_weight"},
                                      std::pair{o.forearm.right_weight, "observation.forearm.right_weight"}}) {
    if (!(weight >= 0.0 && weight <= 1.0)) throw_invalid(field, "not in [0, 1]");
  }
}

double forearm_direction_weight(double axis_rms_rad) {
  if (!(axis_rms_rad >= 0.0)) return 0.0;
  if (axis_rms_rad <= forearm::kConfidentDirectionRmsRad) return 1.0;
  const double ratio = forearm::kConfidentDirectionRmsRad / axis_rms_rad;
  return ratio * ratio;
}

FrameObservation prepare_observation(const DepthFrame& frame, const raycast::DepthCamera& camera,
                                     const std::optional<KinectSkeleton>& skeleton_K, const FitOptions& options,
                                     const ForearmDirections& forearm, ObservationTimes* times) {
  ObservationBuffers buffers;
  prepare_observation(buffers, frame, camera, skeleton_K, options, forearm, times);
  return std::move(buffers.observation);
}

const FrameObservation& prepare_observation(ObservationBuffers& buffers, const DepthFrame& frame,
                                            const raycast::DepthCamera& camera,
                                            const std::optional<KinectSkeleton>& skeleton_K, const FitOptions& options,
                                            const ForearmDirections& forearm, ObservationTimes* times) {
  validate(options);
  validate(frame, camera);
  if (!skeleton_K) throw_precondition("skeleton", "missing: depth sampling needs the camera skeleton (paper 2, II-H)");
  ObservationTimes unused;
  ObservationTimes& t = times ? *times : unused;
  double lap = thread_cpu_seconds();
  // Adds the CPU time since the last lap to `part`.
  const auto take = [&lap](double& part) {
    const double now = thread_cpu_seconds();
    part += now - lap;
    lap = now;
  };
  PointCloud& cloud = buffers.cloud;
  build_point_cloud(frame, camera, cloud);
  take(t.cloud_s);
  ZoneSamplingParams zones;
  zones.num_samples = options.num_samples;
  zones.seed = options.seed;
  const std::vector<DepthSample> samples = sample_depth_pixels(cloud, *skeleton_K, camera, zones);
  take(t.sampling_s);
  FrameObservation& o = buffers.observation;
  o.points_K.clear();
  o.normals_K.clear();
  o.points_K.reserve(samples.size());
  o.normals_K.reserve(samples.size());
  for (const DepthSample& s : samples) {
    const auto normal = estimate_normal_at(cloud, s.col, s.row);
    if (!normal) continue;
    o.points_K.push_back(s.p_K.cast<double>());
    o.normals_K.push_back(normal->cast<double>().normalized());
  }
  if (o.points_K.size() < kMinSamples)
    throw_precondition("frame.depth_mm", std::to_string(o.points_K.size()) +
                                             " depth samples with a surface normal; the fit needs at least " +
                                             std::to_string(kMinSamples));
  take(t.normals_s);
  silhouette_of(frame, buffers.silhouette);
  silhouette_distance_map_near(buffers.silhouette, frame.width, frame.height, o.silhouette);
  take(t.d2d_s);
  if (o.behind) o.behind->rebuild(cloud, camera);
  else o.behind.emplace(cloud, camera);
  take(t.d3d_s);
  o.forearm = forearm;
  validate(o);
  return o;
}

}  // namespace posefuse::fit
