#include "model_frames.hpp"

#include <numbers>

#include "raycast/mesh_scene.hpp"

namespace posefuse::fit::testing {
namespace {
// SMPL joint for each Kinect v2 joint (kKinectJointNames order); hand tips and thumbs use the hand.
constexpr int kSmplForKinect[kKinectJointCount] = {0, 6, 12, 15, 16, 18, 20, 22, 17, 19, 21, 23, 1,
                                                   4, 7, 10, 2,  5,  8,  11, 9,  22, 22, 23, 23};
}  // namespace

ModelFrame render_model_frame(const std::shared_ptr<const body::SmplModel>& model, const body::PoseLayout& layout,
                              const Eigen::VectorXd& beta, const Eigen::VectorXd& theta,
                              const raycast::DepthCamera& camera) {
  body::BodyEvaluator eval(model, layout);
  eval.evaluate(beta, theta, body::Derivatives::kNone);
  raycast::MeshScene scene(raycast::EmbreeDevice::shared(), model->faces, model->num_vertices());
  scene.update_vertices(eval.vertices());
  raycast::RenderImages images;
  scene.render(camera, 0, images);
  ModelFrame out;
  out.frame = {images.width, images.height, images.depth_mm, images.body_index};
  for (int k = 0; k < kKinectJointCount; ++k) out.skeleton_K[k] = eval.joints().col(kSmplForKinect[k]);
  out.joints_K = eval.joints();
  return out;
}

Eigen::VectorXd facing_pose(const body::PoseLayout& layout, double distance_m, int variant) {
  constexpr double deg = std::numbers::pi / 180;
  const double a = 10.0 * (variant % 3), b = 7.0 * (variant % 2);
  Eigen::VectorXd theta = layout.zero();
  theta[layout.index_of("translation_y")] = -0.95;
  theta[layout.index_of("translation_z")] = distance_m;
  theta[layout.index_of("pelvis_y")] = std::numbers::pi;  // face the camera (-z in K)
  theta[layout.index_of("left_shoulder_z")] = (-35 + a) * deg;
  theta[layout.index_of("right_shoulder_z")] = (45 - b) * deg;
  theta[layout.index_of("left_shoulder_y")] = (-20 - b) * deg;
  theta[layout.index_of("right_shoulder_y")] = (25 + a) * deg;
  theta[layout.index_of("left_elbow_y")] = (-60 + a) * deg;
  theta[layout.index_of("right_elbow_y")] = (45 + b) * deg;
  theta[layout.index_of("spine2_x")] = 8 * deg;
  theta[layout.index_of("spine1_z")] = (4 - b) * deg;
  theta[layout.index_of("head_y")] = 10 * deg;
  return theta;
}

Eigen::Vector3d forearm_direction(const Eigen::Matrix3Xd& joints_K, bool left) {
  const int elbow = left ? body::kLeftElbow : body::kRightElbow, wrist = left ? body::kLeftWrist : body::kRightWrist;
  return (joints_K.col(wrist) - joints_K.col(elbow)).normalized();
}

}  // namespace posefuse::fit::testing
