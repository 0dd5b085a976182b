// Speed of the depth preprocessing for model fitting (paper 2, II-D/H; issue 7) on one 512x424
// frame: point cloud, normals of every cloud pixel, silhouette distance map (D_2D), behind-
// surface map (D_3D, 0.02 m), zone sampling of N_s = 250 pixels and the normals of those samples.
// Frames: the built-in body template rendered with Embree at 2.0 m (a realistic silhouette, its
// Kinect-like skeleton taken from the model's joints), and a plane filling the whole image (the
// worst case for per-pixel work). Single-threaded; prints medians of wall and thread CPU time.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <functional>
#include <numbers>
#include <vector>

#include "bench_clock.hpp"
#include "body/body_evaluator.hpp"
#include "body/template_generator.hpp"
#include "fit/behind_surface_map.hpp"
#include "fit/point_normals.hpp"
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

void bench_frame(const char* name, const raycast::DepthCamera& camera, const fit::DepthFrame& frame,
                 const fit::KinectSkeleton& skeleton_K, int repeats) {
  const fit::PointCloud cloud = fit::build_point_cloud(frame, camera);
  std::printf("%-6s %-40s %9d\n", name, "cloud pixels", cloud.count);
  report(name, "point cloud", repeats, [&] { fit::build_point_cloud(frame, camera); });
  report(name, "normals, every cloud pixel", repeats, [&] { fit::estimate_normals(cloud); });
  const std::vector<uint8_t> silhouette = fit::silhouette_of(frame);
  report(name, "silhouette distance map (D_2D)", repeats,
         [&] { fit::silhouette_distance_map(silhouette, frame.width, frame.height); });
  report(name, "behind-surface map (D_3D, 0.02 m)", repeats, [&] { fit::BehindSurfaceMap(frame, camera); });
  const fit::BehindSurfaceMap d3d(frame, camera);
  const Eigen::Vector3i grid = d3d.grid_size();
  std::printf("%-6s %-40s %4d x %d x %d\n", name, "D_3D grid", grid.x(), grid.y(), grid.z());
  report(name, "zone sampling, N_s = 250", repeats, [&] { fit::sample_depth_pixels(cloud, skeleton_K, camera); });
  const auto samples = fit::sample_depth_pixels(cloud, skeleton_K, camera);
  report(name, "normals of the 250 samples", repeats, [&] {
    for (const auto& s : samples) fit::estimate_normal_at(cloud, s.col, s.row);
  });
}

}  // namespace

int main() {
  const raycast::DepthCamera camera{raycast::DepthIntrinsics{}};
  std::printf("Depth preprocessing, 512x424, one thread\n");
  std::printf("%-6s %-40s %12s %12s\n", "frame", "operation", "median wall", "median cpu");
  const BodyFrame body = render_body(camera);
  bench_frame("body", camera, body.frame, body.skeleton_K, 30);
  const fit::DepthFrame plane = fit::testing::render_plane(camera, {0, 0, 2}, Eigen::Vector3d(0.2, 0.1, -1).normalized());
  bench_frame("plane", camera, plane, fit::testing::t_pose_skeleton(2.0), 10);
  return 0;
}
