// Renders the built-in template (male, female; a few poses and shapes) through the depth
// renderer and writes shaded PNGs, so that one can see it looks like a person:
//   bench_render_gallery <output folder>     (docs/images/ in the repository)
// Shading: Lambert on the face normal of the face each pixel sees (from the face id buffer).
#include <Eigen/Geometry>
#include <cstdio>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <utility>
#include <vector>

#include "body/body_evaluator.hpp"
#include "body/template_generator.hpp"
#include "raycast/mesh_scene.hpp"

using namespace posefuse;

namespace {

constexpr double kDeg = std::numbers::pi / 180;

struct View {
  const char* name;
  std::vector<std::pair<const char*, double>> pose_deg;
  std::vector<std::pair<int, double>> beta;
  double yaw_deg = 180;  // 180: facing the camera
};

cv::Mat shade(const raycast::RenderImages& images, const Eigen::Matrix3Xd& vertices, const Eigen::Matrix3Xi& faces,
              const raycast::DepthCamera& camera) {
  cv::Mat out(images.height, images.width, CV_8UC3, cv::Scalar(40, 40, 40));
  for (int row = 0; row < images.height; ++row)
    for (int col = 0; col < images.width; ++col) {
      const int f = images.face[static_cast<size_t>(row) * images.width + col];
      if (f < 0) continue;
      const Eigen::Vector3d a = vertices.col(faces(0, f)), b = vertices.col(faces(1, f)), c = vertices.col(faces(2, f));
      const Eigen::Vector3d n = (b - a).cross(c - a).normalized();
      const Eigen::Vector3d to_camera = -camera.pixel_ray(col, row).cast<double>().normalized();
      const double lambert = std::max(0.0, n.dot(to_camera));
      const auto level = static_cast<unsigned char>(60 + 190 * lambert);
      out.at<cv::Vec3b>(row, col) =
          cv::Vec3b(static_cast<unsigned char>(level * 0.8), static_cast<unsigned char>(level * 0.9), level);
    }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s <output folder>\n", argv[0]);
    return 2;
  }
  const std::string folder = argv[1];
  raycast::DepthIntrinsics intrinsics;
  intrinsics.width = 400;
  intrinsics.height = 480;
  intrinsics.fx = intrinsics.fy = 560;
  intrinsics.cx = 200;
  intrinsics.cy = 240;
  intrinsics.k1 = intrinsics.k2 = intrinsics.k3 = 0;
  const raycast::DepthCamera camera(intrinsics);
  const std::vector<View> views = {
      {"rest", {}, {}},
      {"relaxed",
       {{"left_shoulder_z", -70}, {"right_shoulder_z", 70}, {"left_elbow_y", -20}, {"right_elbow_y", 20}},
       {}},
      {"reach",
       {{"left_shoulder_z", 60},
        {"left_elbow_y", -30},
        {"right_shoulder_y", 70},
        {"right_elbow_y", 90},
        {"spine2_z", -10},
        {"head_y", 20}},
       {}},
      {"side",
       {{"left_shoulder_z", -60},
        {"left_shoulder_y", -60},
        {"left_elbow_y", -90},
        {"right_shoulder_z", 75},
        {"left_hip_x", -60},
        {"left_knee_x", 80},
        {"spine1_x", 15}},
       {},
       120},
      {"shapes", {{"left_shoulder_z", -50}, {"right_shoulder_z", 50}}, {{0, 2}, {7, 2}, {8, 1.5}, {6, 2}}},
      {"slim", {{"left_shoulder_z", -50}, {"right_shoulder_z", 50}}, {{0, -1.5}, {7, -2}, {8, -1.5}, {5, 2}}},
  };
  for (body::Sex sex : {body::Sex::kMale, body::Sex::kFemale}) {
    const auto model = body::make_template(sex);
    const body::PoseLayout layout = body::PoseLayout::full_body();
    body::BodyEvaluator eval(model, layout);
    raycast::MeshScene scene(raycast::EmbreeDevice::shared(), model->faces, model->num_vertices());
    std::vector<cv::Mat> tiles;
    for (const View& view : views) {
      Eigen::VectorXd theta = layout.zero();
      for (const auto& [name, value] : view.pose_deg) theta[layout.index_of(name)] = value * kDeg;
      theta[layout.index_of("pelvis_y")] = view.yaw_deg * kDeg;
      theta[layout.index_of("translation_y")] = -0.92;
      theta[layout.index_of("translation_z")] = 2.6;
      Eigen::VectorXd beta = Eigen::VectorXd::Zero(10);
      for (const auto& [index, value] : view.beta) beta[index] = value;
      eval.evaluate(beta, theta, body::Derivatives::kNone);
      scene.update_vertices(eval.vertices());
      raycast::RenderImages images;
      scene.render(camera, 0, images);
      cv::Mat tile = shade(images, eval.vertices(), model->faces, camera);
      cv::putText(tile, view.name, {8, 24}, cv::FONT_HERSHEY_SIMPLEX, 0.7, cv::Scalar(255, 255, 255), 1);
      tiles.push_back(tile);
      if (std::string(view.name) == "reach") {  // also the raw 16-bit depth, as the camera gives it
        cv::Mat depth(images.height, images.width, CV_16UC1, images.depth_mm.data());
        cv::imwrite(folder + "/template_" + (sex == body::Sex::kMale ? "male" : "female") + "_depth_mm.png", depth);
      }
    }
    cv::Mat strip;
    cv::hconcat(tiles, strip);
    const std::string path = folder + "/template_" + (sex == body::Sex::kMale ? "male" : "female") + ".png";
    cv::imwrite(path, strip);
    std::printf("wrote %s (%d vertices, %d faces)\n", path.c_str(), model->num_vertices(), model->num_faces());
  }
  return 0;
}
