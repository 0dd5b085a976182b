#pragma once
// RGB frames for strap detection (paper 1, II-H): the posed render model seen by a colour
// camera next to the depth camera, coloured by material (skin, shirt, trousers, shoes, hair),
// with a black strap band around each forearm that carries an IMU, the room (floor, wall)
// behind, Lambertian shading, per-channel Gaussian noise and JPEG compression.
//
// Speed: the room is static, so its colours are computed once; the noise is a pool of Gaussian
// values drawn once per session (an image plus a 64 px margin) from which every frame takes a
// window at a random offset. Neighbouring frames therefore see shifted copies of one noise
// field rather than fresh draws: enough for detection tests, far cheaper than 1.5 M normal
// draws per frame.
//
// Frame C of the colour camera has K's axes (x left, y up, z forward) and projects like the
// depth camera (raycast/depth_camera.hpp, no distortion by default); p_C = color_from_depth *
// p_K, as SessionHeader.color_from_depth. Pixels are rendered by ray casting the same mesh as
// the depth camera (raycast::MeshScene face ids and barycentrics).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "posefuse/v1/session.pb.h"
#include "raycast/depth_camera.hpp"
#include "raycast/mesh_scene.hpp"
#include "sim/depth_noise.hpp"
#include "sim/render_model.hpp"

namespace posefuse::sim {

struct ColorCameraOptions {
  // Kinect v2's 1920 x 1080 colour camera at half resolution, without distortion.
  raycast::DepthIntrinsics intrinsics{960, 540, 528.0, 528.0, 479.5, 269.5, 0.0, 0.0, 0.0};
  // The colour camera 5.2 cm to the depth camera's right (K's -x), turned 0.5 deg about y.
  Eigen::Isometry3d color_from_depth =
      Eigen::AngleAxisd(0.5 * 3.14159265358979323846 / 180.0, Eigen::Vector3d::UnitY()) *
      Eigen::Translation3d(0.052, 0.0, 0.0);
  double noise_sigma = 3.0;     // per channel, of 255
  int jpeg_quality = 90;        // 1..100
  double strap_width_m = 0.03;  // strap band along the forearm, centred at d_se
};

void validate(const ColorCameraOptions& options);  // kInvalidArgument naming the field

// Straps per arm (0 left, 1 right): centre distance from the elbow, or NaN for no strap.
using StrapPlacement = std::array<double, 2>;

// Whether the render model's face `face` at barycentrics (u, v) lies on a strap band of width
// `width_m` (the forearm coordinate interpolated from the face's corners).
bool is_strap(const RenderModel& model, const StrapPlacement& straps, double width_m, int face, double u, double v);

class ColorRenderer {
 public:
  // room_K: the room planes in K, plane 0 the floor; seed: the session's.
  ColorRenderer(const ColorCameraOptions& options, const RenderModel& model, const StrapPlacement& straps,
                const std::vector<RoomPlane>& room_K, std::uint64_t seed);

  // vertices_K: the posed render model in K (3 x V). 8-bit BGR image.
  cv::Mat render(const Eigen::Matrix3Xd& vertices_K, std::int64_t frame);

  const raycast::DepthCamera& camera() const { return camera_; }

 private:
  ColorCameraOptions options_;
  raycast::DepthCamera camera_;
  raycast::MeshScene scene_;
  const RenderModel& model_;
  StrapPlacement straps_;
  std::uint64_t seed_;
  cv::Mat background_;  // CV_16SC3, the room
  cv::Mat noise_;       // CV_16SC3, image size plus kNoiseMargin each way
  raycast::RenderImages images_;
  Eigen::Matrix3Xd face_normals_;  // of the current frame, in C
};

// JPEG bytes of a BGR image as a ColorFrame.
v1::ColorFrame encode_color_frame(const cv::Mat& bgr, int jpeg_quality, std::int64_t t_us);

}  // namespace posefuse::sim
