// Speed of the depth preprocessing for model fitting (paper 2, II-D/H; issue 7) on one 512x424
// frame: point cloud, normals of every cloud pixel, silhouette distance map (D_2D), behind-
// surface map (D_3D, 0.02 m: the first full-grid version and today's query-time search), zone sampling of N_s = 250
// pixels and the normals of those samples. Frames: the built-in body template rendered with Embree at 2.0 m (a
// realistic silhouette, its Kinect-like skeleton taken from the model's joints), and a plane filling the whole image
// (the worst case for per-pixel work). Single-threaded; prints medians of wall and thread CPU time.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <functional>
#include <numbers>
#include <random>
#include <vector>

#include "bench_clock.hpp"
#include "body/body_evaluator.hpp"
#include "body/template_generator.hpp"
#include "dense_behind_surface.hpp"
#include "fit/behind_surface_map.hpp"
#include "fit/frame_observation.hpp"
#include "fit/packed_body_frame.hpp"
#include "fit/point_normals.hpp"
#include "fit/silhouette_cleanup.hpp"
#include "fit/silhouette_distance.hpp"
#include "fit/zone_sampling.hpp"
#include "model_frames.hpp"
#include "synthetic_frames.hpp"

using namespace posefuse;

namespace {

// Median wall and thread-CPU milliseconds over `repeats` calls after one warm-up call.
void report(const char* frame_name, const char* operation, int repeats, const std::function<void()>& fn) {
  fn();
  std::vector<double> wall, cpu;
  for (int i = 0; i < repeats; ++i) {
    const auto start = std::chrono::steady_clock::now();
    const double cpu_start = 1e3 * posefuse::bench::thread_cpu_seconds();
    fn();
    cpu.push_back(1e3 * posefuse::bench::thread_cpu_seconds() - cpu_start);
    wall.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
  std::sort(wall.begin(), wall.end());
  std::sort(cpu.begin(), cpu.end());
  std::printf("%-6s %-40s %9.2f ms %9.2f ms\n", frame_name, operation, wall[repeats / 2], cpu[repeats / 2]);
}

struct BodyFrame {
  fit::DepthFrame frame;
  fit::KinectSkeleton skeleton_K;
};

BodyFrame render_body(const raycast::DepthCamera& camera) {
  constexpr double deg = std::numbers::pi / 180;
  const auto model = body::make_template(body::Sex::kMale);
  const body::PoseLayout layout = body::PoseLayout::upper_body();
  Eigen::VectorXd theta = layout.zero();
  theta[layout.index_of("translation_y")] = -0.9;
  theta[layout.index_of("translation_z")] = 2.0;
  theta[layout.index_of("pelvis_y")] = std::numbers::pi;  // face the camera
  theta[layout.index_of("left_shoulder_z")] = -40 * deg;
  theta[layout.index_of("right_shoulder_z")] = 50 * deg;
  theta[layout.index_of("left_elbow_y")] = -70 * deg;
  const auto rendered = fit::testing::render_model_frame(model, layout, Eigen::VectorXd::Zero(10), theta, camera);
  return {rendered.frame, rendered.skeleton_K};
}

// Float points as the fitter selects them (paper 2, II-D.6): inside the silhouette when
// projected, but in front of the observed surface.
std::vector<Eigen::Vector3d> float_like_points(const fit::PointCloud& cloud, const fit::BehindSurfaceMap& map,
                                               const raycast::DepthCamera& camera, int count) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<Eigen::Vector3d> points;
  while (static_cast<int>(points.size()) < count) {
    const size_t pixel = static_cast<size_t>(uniform(rng) * cloud.valid.size());
    if (!cloud.valid[pixel]) continue;
    const Eigen::Vector3d p =
        cloud.value_K[pixel].cast<double>() +
        Eigen::Vector3d(0.04 * (uniform(rng) - 0.5), 0.04 * (uniform(rng) - 0.5), -0.1 * uniform(rng));
    const auto uv = camera.project(p);
    if (!uv || map.is_behind(p)) continue;
    const int col = static_cast<int>(std::lround(uv->x())), row = static_cast<int>(std::lround(uv->y()));
    if (col < 0 || row < 0 || col >= cloud.width || row >= cloud.height || !cloud.has(col, row)) continue;
    points.push_back(p);
  }
  return points;
}

void bench_frame(const char* name, const raycast::DepthCamera& camera, const fit::DepthFrame& frame,
                 const fit::KinectSkeleton& skeleton_K, int repeats) {
  const fit::PointCloud cloud = fit::build_point_cloud(frame, camera);
  std::printf("%-6s %-40s %9d\n", name, "cloud pixels", cloud.count);
  report(name, "point cloud", repeats, [&] { fit::build_point_cloud(frame, camera); });
  report(name, "normals, every cloud pixel", repeats, [&] { fit::estimate_normals(cloud); });
  const std::vector<uint8_t> silhouette = fit::silhouette_of(frame);
  report(name, "silhouette distance map (D_2D)", repeats,
         [&] { fit::silhouette_distance_map(silhouette, frame.width, frame.height); });
  const fit::BehindSurfaceMap d3d(frame, camera);
  const Eigen::Vector3i grid = d3d.grid_size();
  std::printf("%-6s %-40s %4d x %d x %d\n", name, "D_3D grid", grid.x(), grid.y(), grid.z());
  report(name, "D_3D before: full grid + EDT (reference)", repeats,
         [&] { fit::testing::dense_behind_distance2(fit::BehindSurfaceMap(frame, camera)); });
  report(name, "D_3D map construction (query-time search)", repeats, [&] { fit::BehindSurfaceMap(frame, camera); });
  // A fitter's load: float points (paper 2: a subset of H_max = 150 bg points) over 20 LM
  // iterations, each a cloud point pushed up to 0.1 m towards the camera and 2 cm sideways, kept
  // when it still projects into the silhouette.
  const std::vector<Eigen::Vector3d> floating = float_like_points(cloud, d3d, camera, 20 * 150);
  report(name, "D_3D map + 3000 float-point queries", repeats, [&] {
    const fit::BehindSurfaceMap map(frame, camera);
    for (const auto& p : floating) map.closest_behind(p);
  });
  report(name, "D_3D map + 3000 queries, cached", repeats, [&] {
    const fit::BehindSurfaceMap map(frame, camera);
    fit::BehindSurfaceCache cache;
    for (const auto& p : floating) map.closest_behind(p, cache);
  });
  report(name, "zone sampling, N_s = 250", repeats, [&] { fit::sample_depth_pixels(cloud, skeleton_K, camera); });
  const auto samples = fit::sample_depth_pixels(cloud, skeleton_K, camera);
  report(name, "normals of the 250 samples", repeats, [&] { fit::estimate_sample_normals(cloud, samples); });
  // The body-fit stage's whole per-frame path: the queued frame unpacked, cleaned, preprocessed.
  const fit::PackedBodyFrame packed = fit::pack_body_pixels(frame);
  const fit::TrackedSkeleton tracked = fit::TrackedSkeleton::all_tracked(skeleton_K);
  const fit::FitOptions options;
  report(name, "unpack + cleanup + prepare_observation", repeats, [&] {
    fit::DepthFrame unpacked = fit::unpack_body_pixels(packed);
    fit::remove_off_body_depth(unpacked, tracked);
    fit::prepare_observation(unpacked, camera, skeleton_K, options);
  });
  // The same with the buffers kept from frame to frame, as the body tracker runs it.
  fit::ObservationBuffers buffers;
  report(name, "the same, buffers reused", repeats, [&] {
    fit::DepthFrame unpacked = fit::unpack_body_pixels(packed);
    fit::remove_off_body_depth(unpacked, tracked);
    fit::prepare_observation(buffers, unpacked, camera, skeleton_K, options);
  });
  // Its parts with the buffers reused, thread CPU medians over the same number of calls.
  std::vector<double> unpack_ms, cleanup_ms, cloud_ms, sampling_ms, normals_ms, d2d_ms, d3d_ms;
  for (int i = 0; i < repeats; ++i) {
    double lap = 1e3 * posefuse::bench::thread_cpu_seconds();
    const auto take = [&lap](std::vector<double>& part) {
      const double now = 1e3 * posefuse::bench::thread_cpu_seconds();
      part.push_back(now - lap);
      lap = now;
    };
    fit::DepthFrame unpacked = fit::unpack_body_pixels(packed);
    take(unpack_ms);
    fit::remove_off_body_depth(unpacked, tracked);
    take(cleanup_ms);
    fit::ObservationTimes times;
    fit::prepare_observation(buffers, unpacked, camera, skeleton_K, options, {}, &times);
    for (auto [part, s] : {std::pair{&cloud_ms, times.cloud_s},
                           {&sampling_ms, times.sampling_s},
                           {&normals_ms, times.normals_s},
                           {&d2d_ms, times.d2d_s},
                           {&d3d_ms, times.d3d_s}})
      part->push_back(1e3 * s);
  }
  const auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  std::printf(
      "%-6s   of which: unpack %.2f, cleanup %.2f, cloud %.2f, zones %.2f, normals %.2f, D_2D %.2f, D_3D %.2f ms\n",
      name, median(unpack_ms), median(cleanup_ms), median(cloud_ms), median(sampling_ms), median(normals_ms),
      median(d2d_ms), median(d3d_ms));
}

}  // namespace

int main() {
  const raycast::DepthCamera camera{raycast::DepthIntrinsics{}};
  std::printf("Depth preprocessing, 512x424, one thread\n");
  std::printf("%-6s %-40s %12s %12s\n", "frame", "operation", "median wall", "median cpu");
  const BodyFrame body = render_body(camera);
  bench_frame("body", camera, body.frame, body.skeleton_K, 30);
  const fit::DepthFrame plane =
      fit::testing::render_plane(camera, {0, 0, 2}, Eigen::Vector3d(0.2, 0.1, -1).normalized());
  bench_frame("plane", camera, plane, fit::testing::t_pose_skeleton(2.0), 10);
  return 0;
}
