// Speed of the body model and its rendering (issue 3): model evaluation with and without
// Jacobians, BVH refit, and a 512x424 depth + body index render of the posed built-in template.
// Single-threaded (Embree device with threads=1). Prints a table of medians.
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
#include "raycast/mesh_scene.hpp"

using namespace posefuse;

namespace {

// Medians over `repeats` calls (after 3 warm-up calls) of the wall time and of the CPU time of
// this thread, in microseconds. On a shared machine the wall time includes waiting for a core;
// the thread CPU time does not.
struct Timing {
  double wall_us, cpu_us;
};
Timing median_us(int repeats, const std::function<void()>& fn) {
  for (int i = 0; i < 3; ++i) fn();
  std::vector<double> wall, cpu;
  for (int i = 0; i < repeats; ++i) {
    const auto start = std::chrono::steady_clock::now();
    const double cpu_start = 1e6 * posefuse::bench::thread_cpu_seconds();
    fn();
    cpu.push_back(1e6 * posefuse::bench::thread_cpu_seconds() - cpu_start);
    wall.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count());
  }
  std::nth_element(wall.begin(), wall.begin() + repeats / 2, wall.end());
  std::nth_element(cpu.begin(), cpu.begin() + repeats / 2, cpu.end());
  return {wall[repeats / 2], cpu[repeats / 2]};
}

void print_row(const char* model, const char* operation, Timing t) {
  std::printf("%-8s %-44s %10.1f us %10.1f us\n", model, operation, t.wall_us, t.cpu_us);
}

// The template facing the camera 2.5 m away, arms half raised, elbows and spine bent.
Eigen::VectorXd demo_pose(const body::PoseLayout& layout) {
  constexpr double deg = std::numbers::pi / 180;
  Eigen::VectorXd theta = layout.zero();
  theta[layout.index_of("translation_y")] = -1.08;
  theta[layout.index_of("translation_z")] = 2.5;
  theta[layout.index_of("pelvis_y")] = std::numbers::pi;  // face the camera (-z in K)
  theta[layout.index_of("left_shoulder_z")] = -40 * deg;
  theta[layout.index_of("right_shoulder_z")] = 50 * deg;
  theta[layout.index_of("left_elbow_y")] = -70 * deg;
  theta[layout.index_of("right_shoulder_y")] = 40 * deg;
  theta[layout.index_of("spine2_x")] = 10 * deg;
  return theta;
}

}  // namespace

int main() {
  std::printf("Body model and rendering (one thread)\n");
  std::printf("%-8s %-44s %13s %13s\n", "model", "operation", "median wall", "median cpu");
  for (body::Sex sex : {body::Sex::kMale, body::Sex::kFemale}) {
    const char* name = sex == body::Sex::kMale ? "male" : "female";
    const auto model = body::make_template(sex);
    const body::PoseLayout layout = body::PoseLayout::upper_body();
    body::BodyEvaluator eval(model, layout);
    const Eigen::VectorXd beta = Eigen::VectorXd::Constant(10, 0.3);
    const Eigen::VectorXd theta = demo_pose(layout);

    const Timing t_none = median_us(2000, [&] { eval.evaluate(beta, theta, body::Derivatives::kNone); });
    const Timing t_pose = median_us(2000, [&] { eval.evaluate(beta, theta, body::Derivatives::kPose); });
    const Timing t_shape = median_us(500, [&] { eval.evaluate(beta, theta, body::Derivatives::kPoseAndShape); });
    print_row(name, "evaluate, no derivatives", t_none);
    print_row(name, "evaluate + pose Jacobian (40 DOF)", t_pose);
    print_row(name, "evaluate + pose and shape Jacobians", t_shape);

    eval.evaluate(beta, theta, body::Derivatives::kNone);
    raycast::MeshScene scene(raycast::EmbreeDevice::shared(), model->faces, model->num_vertices());
    const raycast::DepthCamera camera{raycast::DepthIntrinsics{}};
    raycast::RenderImages images;
    const Timing t_refit = median_us(500, [&] { scene.update_vertices(eval.vertices()); });
    const Timing t_render = median_us(200, [&] { scene.render(camera, 0, images); });
    const Timing t_frame = median_us(200, [&] {
      eval.evaluate(beta, theta, body::Derivatives::kNone);
      scene.update_vertices(eval.vertices());
      scene.render(camera, 0, images);
    });
    int hits = 0;
    for (uint16_t d : images.depth_mm) hits += d > 0;
    print_row(name, "BVH refit (update_vertices)", t_refit);
    print_row(name, "render 512x424 depth+index+face+bary", t_render);
    print_row(name, "frame: evaluate + refit + render", t_frame);
    std::printf("%-8s %-44s %9d\n", name, "body pixels", hits);
  }
  return 0;
}
