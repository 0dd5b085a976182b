#include "sim/camera_session.hpp"

#include <cmath>
#include <numbers>
#include <opencv2/core.hpp>
#include <string>

#include "body/body_evaluator.hpp"
#include "common/error.hpp"
#include "raycast/mesh_scene.hpp"
#include "session/image_codec.hpp"
#include "session/session_inputs.hpp"
#include "session/session_validator.hpp"
#include "sim/option_checks.hpp"

namespace posefuse::sim {
namespace {

using std::numbers::pi;

v1::SessionHeader make_header(const CameraSessionOptions& options) {
  v1::SessionHeader h;
  h.set_format_version(session::kFormatVersion);
  h.set_subject_id("sim");
  h.set_sex(options.sex == body::Sex::kMale ? v1::SessionHeader::MALE : v1::SessionHeader::FEMALE);
  set_camera_intrinsics(options.intrinsics, h.mutable_depth_intrinsics());
  h.set_depth_rate_hz(options.rate_hz);
  return h;
}

}  // namespace

void set_camera_intrinsics(const raycast::DepthIntrinsics& in, v1::CameraIntrinsics* out) {
  *out = session::camera_intrinsics(in);
}

PoseSequence arm_raising_sequence(const body::PoseLayout& layout, double period_s) {
  require_positive(period_s, "period_s");
  const int left = layout.index_of("left_shoulder_z");
  const int right = layout.index_of("right_shoulder_z");
  const int size = layout.size();
  return [=](double t_s) {
    Eigen::VectorXd theta = Eigen::VectorXd::Zero(size);
    // In the T-pose the left arm points along +x; about z, negative turns it down.
    const double raise = 0.5 * (1.0 - std::cos(2 * pi * t_s / period_s));  // 0 -> 1 -> 0
    const double angle = (-75.0 + 150.0 * raise) * pi / 180.0;
    theta[left] = angle;
    theta[right] = -angle;
    return theta;
  };
}

CameraSessionResult simulate_camera_session(const CameraSessionOptions& options, const body::PoseLayout& layout,
                                            const PoseSequence& poses) {
  require_positive(options.rate_hz, "rate_hz");
  require_positive(options.duration_s, "duration_s");
  require_positive(options.wall_distance_m, "wall_distance_m");
  if (!options.K_from_W.matrix().allFinite()) throw_invalid("K_from_W", "is not finite");
  if (options.body_id > session::kMaxBodyId) {
    throw_invalid("body_id", "is " + std::to_string(options.body_id) + ", must be 0..5");
  }
  validate(options.depth_noise);
  for (const ForearmStrap& strap : options.forearm_straps) validate(strap);
  if (!poses) throw_invalid("poses", "is empty");
  const raycast::DepthCamera camera(options.intrinsics);  // validates the intrinsics
  const auto model = body::make_template(options.sex);
  body::BodyEvaluator evaluator(model, layout);
  raycast::MeshScene scene(raycast::EmbreeDevice::shared(), model->faces, model->num_vertices());
  const CameraSkeletonSimulator skeleton(camera, options.skeleton, options.seed, *model);

  // The floor y_W = 0 in K: normal R e_y through the point t (W's origin).
  const Eigen::Vector3d floor_normal_K = options.K_from_W.linear() * Eigen::Vector3d::UnitY();
  const std::vector<RoomPlane> room = {RoomPlane{floor_normal_K, floor_normal_K.dot(options.K_from_W.translation())},
                                       RoomPlane{Eigen::Vector3d::UnitZ(), options.wall_distance_m}};

  CameraSessionResult result;
  result.header = make_header(options);
  const auto frames = static_cast<std::int64_t>(std::floor(options.duration_s * options.rate_hz + 1e-9)) + 1;
  raycast::RenderImages images;
  for (std::int64_t f = 0; f < frames; ++f) {
    const double t_s = static_cast<double>(f) / options.rate_hz;
    const std::int64_t t_us = std::llround(t_s * 1e6);
    const Eigen::VectorXd theta = poses(t_s);
    if (theta.size() != layout.size() || !theta.allFinite()) {
      throw_invalid("poses", "frame " + std::to_string(f) + " gave " + std::to_string(theta.size()) +
                                 " values (layout has " + std::to_string(layout.size()) + ") or non-finite ones");
    }
    evaluator.evaluate(options.betas, theta, body::Derivatives::kNone);
    scene.update_vertices(options.K_from_W * evaluator.vertices());
    scene.render(camera, static_cast<std::uint8_t>(options.body_id), images);
    composite_room(camera, room, images.depth_mm);
    const NoisyDepth noisy =
        apply_depth_noise(camera, images.depth_mm, images.body_index, options.depth_noise, options.seed, f);
    const SmplJointsK joints = smpl_joints_in_camera(evaluator, options.K_from_W);

    // cv::Mat views of the images (the codec copies the pixels).
    const cv::Mat depth(camera.height(), camera.width(), CV_16UC1, const_cast<std::uint16_t*>(noisy.depth_mm.data()));
    const cv::Mat body_index(camera.height(), camera.width(), CV_8UC1,
                             const_cast<std::uint8_t*>(noisy.body_index.data()));
    result.chunks.emplace_back().mutable_depth()->CopyFrom(
        session::encode_depth(depth, v1::DepthFrame::ZSTD_U16_LE, t_us));
    result.chunks.emplace_back().mutable_body_index()->CopyFrom(
        session::encode_body_index(body_index, v1::BodyIndexFrame::ZSTD_U8, t_us));
    result.chunks.emplace_back().mutable_skeleton()->CopyFrom(
        skeleton.simulate(joints, noisy.depth_mm, images.face, f, t_us, options.body_id));
    result.t_us.push_back(t_us);
    result.true_camera_joints_K.push_back(camera_joints_from_smpl(joints));
    result.truth.push_back(frame_truth(evaluator, scene, options.K_from_W, options.forearm_straps));
  }
  return result;
}

}  // namespace posefuse::sim
