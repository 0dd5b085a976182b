#include "table1_session.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <string>

#include <opencv2/core.hpp>

#include "body/pose_parameters.hpp"
#include "forearm/synthetic_images.hpp"
#include "session/image_codec.hpp"
#include "session/text_fields.hpp"
#include "sim/body_imu.hpp"
#include "sim/camera_session.hpp"
#include "sim/imu_device.hpp"
#include "sim/room_frame.hpp"
#include "sim/skeleton_pose.hpp"
#include "sim/sync_signals.hpp"

namespace posefuse::bench {

namespace {

using geometry::Quat;
using geometry::Vec3;

struct Timed {
  double key_s;
  v1::SessionChunk chunk;
};

v1::CameraIntrinsics intrinsics(const geometry::PinholeCamera& c) {
  v1::CameraIntrinsics k;
  k.set_width(static_cast<std::uint32_t>(c.width));
  k.set_height(static_cast<std::uint32_t>(c.height));
  k.set_fx(c.fx);
  k.set_fy(c.fy);
  k.set_cx(c.cx);
  k.set_cy(c.cy);
  k.set_k1(c.k1);
  k.set_k2(c.k2);
  k.set_k3(c.k3);
  k.set_p1(c.p1);
  k.set_p2(c.p2);
  return k;
}

// Noise only (no bias, scale or iron errors): the IMU orientation stage is not what Table I
// measures, and paper 1 calibrates its IMUs beforehand (II-C).
sim::ImuDeviceOptions imu_options(std::uint64_t seed) {
  sim::ImuDeviceOptions o;
  o.synth.error_model = sim::ImuErrorModel::none();
  const sim::ImuErrorModel typical;
  o.synth.error_model.gyr_noise_density_rad_s_sqrt_hz = typical.gyr_noise_density_rad_s_sqrt_hz;
  o.synth.error_model.acc_noise_density_m_s2_sqrt_hz = typical.acc_noise_density_m_s2_sqrt_hz;
  o.synth.error_model.mag_noise_uT = typical.mag_noise_uT;
  o.synth.seed = seed;
  o.packet_loss.loss_rate = 0.0;
  return o;
}

std::string quat_option(const Quat& q) {
  std::ostringstream s;
  s.precision(17);
  s << q.w() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z();
  return s.str();
}

}  // namespace

Table1Session simulate_table1_session(const sim::BodyMotion& motion, const Table1SessionOptions& o) {
  const double duration_s = o.duration_s > 0.0 ? std::min(o.duration_s, motion.duration_s) : motion.duration_s;
  const double heading_rad = 0.4;
  const Quat W_from_R = sim::W_from_R(heading_rad);

  // Camera: the body, its SDK skeleton and the forearm truth. The skeleton's occlusion test
  // uses a half-resolution Kinect depth image (4x fewer pixels to render and perturb).
  sim::CameraSessionOptions camera;
  camera.duration_s = duration_s;
  camera.intrinsics.width = 256;
  camera.intrinsics.height = 212;
  camera.intrinsics.fx = camera.intrinsics.fy = 182.5;
  camera.intrinsics.cx = 128.0;
  camera.intrinsics.cy = 106.0;
  camera.forearm_straps = {o.strap};
  camera.seed = o.seed;
  if (!o.sdk_joint_errors) {
    sim::CameraSkeletonOptions& k = camera.skeleton;
    k.upper_limb_bias_min_m = k.upper_limb_bias_max_m = k.other_bias_min_m = k.other_bias_max_m = 0.0;
    k.jitter_sigma_m = k.inferred_error_m = k.inferred_shoulder_drop_m = 0.0;
    k.jump_probability = k.hand_flip_probability = 0.0;
  }
  const sim::CameraSessionResult shot =
      sim::simulate_camera_session(camera, body::PoseLayout::all_joints(), motion.poses);

  // IMUs on their own clocks.
  const sim::SimDevice arm_device{"arm_r", sim::DeviceClock{3.2, 30e-6}};
  const sim::SimDevice base_device{"base", sim::DeviceClock{-1.7, -20e-6}};
  sim::BaseImuMount mount;
  mount.K_from_B = geometry::quat_from_rotation_vector(Vec3(0.1, 2.0, -0.2));
  const sim::ImuDeviceResult base_imu = sim::simulate_imu_device(
      sim::SensorKinematics(sim::base_imu_trajectory(camera.K_from_W, W_from_R, mount, -0.05, duration_s + 0.05)),
      base_device, imu_options(o.seed + 1), 0.0, duration_s);
  const Eigen::Matrix3Xd rest = sim::template_rest_joints(camera.sex, camera.betas);
  const sim::ImuDeviceResult arm_imu = sim::simulate_imu_device(
      sim::SensorKinematics(sim::forearm_imu_trajectory(motion, rest, o.strap, W_from_R)), arm_device,
      imu_options(o.seed + 2), 0.0, duration_s);

  std::vector<Timed> timed;
  std::map<std::string, std::uint64_t> imu_counts;
  for (const auto* device : {&base_imu, &arm_imu}) {
    const sim::DeviceClock& clock = device == &base_imu ? base_device.clock : arm_device.clock;
    for (const v1::ImuBatch& batch : device->batches) {
      imu_counts[batch.device_id()] += static_cast<std::uint64_t>(batch.t_us_size());
      v1::SessionChunk chunk;
      *chunk.mutable_imu() = batch;
      timed.push_back({clock.to_camera_s(batch.t_us(batch.t_us_size() - 1)), std::move(chunk)});
    }
  }

  // Sync (paper 1, II-G): the buzzer stops at 1.2 s camera time; BLE broadcasts from 0.5 s.
  sim::BuzzerOptions buzzer;
  buzzer.stop_device_us = base_device.clock.to_device_us(1.2);
  sim::AudioOptions audio;
  audio.duration_s = 2.5;
  const sim::BuzzerResult sound = sim::buzzer_stop(base_device, buzzer, audio, o.seed + 3);
  std::uint64_t audio_frames = 0;
  for (const v1::AudioChunk& a : sound.audio) {
    audio_frames += a.pcm_s16le().size() / 2;
    v1::SessionChunk chunk;
    *chunk.mutable_audio() = a;
    timed.push_back({static_cast<double>(a.t_us()) * 1e-6, std::move(chunk)});
  }
  std::uint64_t sync_events = 1;
  {
    v1::SessionChunk chunk;
    *chunk.mutable_sync_event() = sound.stop_event;
    timed.push_back({1.2, std::move(chunk)});
  }
  const sim::BleBroadcastResult receipts =
      sim::ble_broadcast_receipts({base_device, arm_device}, sim::BleBroadcastOptions{}, o.seed + 4);
  for (const v1::SyncEvent& e : receipts.events) {
    const sim::DeviceClock& clock = e.device_id() == "base" ? base_device.clock : arm_device.clock;
    v1::SessionChunk chunk;
    *chunk.mutable_sync_event() = e;
    timed.push_back({clock.to_camera_s(e.t_us()), std::move(chunk)});
    ++sync_events;
  }

  // Per frame: the SDK skeleton, and colour + depth of the forearm with the strap where visible.
  const forearm::StrapCameras cameras = forearm::testing::test_cameras();
  Table1Session session;
  const std::size_t frames = shot.t_us.size();
  for (std::size_t f = 0; f < frames; ++f) {
    const std::int64_t t_us = shot.t_us[f];
    const double t_s = static_cast<double>(t_us) * 1e-6;
    const sim::ForearmTruth& truth = shot.truth[f].forearms.at(0);
    session.frame_t_us.push_back(t_us);
    session.forearm.push_back(truth);
    if (f == 0) session.d_sw_m = (truth.wrist_K_m - truth.strap_K_m).norm();

    forearm::testing::ForearmScene scene;
    scene.elbow_K = truth.elbow_K_m;
    scene.wrist_K = truth.wrist_K_m;
    scene.radius_m = o.strap.strap_radius_m;
    scene.strap_to_elbow_m = o.strap.strap_to_elbow_m;
    scene.strap_visible = !truth.occluded;
    scene.wall_z_m = camera.wall_distance_m;
    const forearm::testing::ForearmImages images =
        forearm::testing::render_forearm(scene, cameras, 6.0, 0.002, o.seed * 100000 + f);
    v1::SessionChunk depth, color;
    *depth.mutable_depth() = session::encode_depth(
        cv::Mat(cameras.depth.height, cameras.depth.width, CV_16UC1, const_cast<std::uint16_t*>(images.depth_mm.data())),
        v1::DepthFrame::PNG16, t_us);
    *color.mutable_color() = session::encode_color_png(
        cv::Mat(cameras.color.height, cameras.color.width, CV_8UC1, const_cast<std::uint8_t*>(images.gray.data())), t_us);
    timed.push_back({t_s, std::move(depth)});
    timed.push_back({t_s + 1e-6, std::move(color)});
    // shot.chunks per frame: depth, body index, skeleton; only the skeleton is used (see the header).
    v1::SessionChunk skeleton = shot.chunks[3 * f + 2];
    timed.push_back({t_s + 2e-6, std::move(skeleton)});
  }
  std::stable_sort(timed.begin(), timed.end(), [](const Timed& a, const Timed& b) { return a.key_s < b.key_s; });

  v1::SessionChunk header;
  v1::SessionHeader& h = *header.mutable_header();
  h = shot.header;
  h.set_subject_id("table1");
  for (const auto& [id, role] : {std::pair{"arm_r", v1::ImuDevice::ARM_RIGHT}, std::pair{"base", v1::ImuDevice::BASE}}) {
    v1::ImuDevice& d = *h.add_imu_devices();
    d.set_device_id(id);
    d.set_role(role);
    d.set_nominal_rate_hz(80.0);
  }
  *h.mutable_depth_intrinsics() = intrinsics(cameras.depth);
  *h.mutable_color_intrinsics() = intrinsics(cameras.color);
  v1::Quaternion& r = *h.mutable_color_from_depth()->mutable_rotation();
  r.set_w(cameras.color_from_depth.w());
  r.set_x(cameras.color_from_depth.x());
  r.set_y(cameras.color_from_depth.y());
  r.set_z(cameras.color_from_depth.z());
  v1::Vec3& tr = *h.mutable_color_from_depth()->mutable_translation_m();
  tr.set_x(cameras.color_from_depth_m.x());
  tr.set_y(cameras.color_from_depth_m.y());
  tr.set_z(cameras.color_from_depth_m.z());
  h.set_color_rate_hz(camera.rate_hz);
  h.set_audio_sample_rate_hz(audio.sample_rate_hz);
  h.set_audio_channels(1);
  (*h.mutable_options())["forearm.K_from_B"] = quat_option(mount.K_from_B);
  (*h.mutable_options())["forearm.calibration_s"] = session::format_double(o.calibration_end_s);
  session.chunks.push_back(std::move(header));
  for (Timed& t : timed) session.chunks.push_back(std::move(t.chunk));

  v1::SessionChunk end;
  v1::EndOfSession& e = *end.mutable_end();
  e.set_depth_frames(frames);
  e.set_skeleton_frames(frames);
  e.set_color_frames(frames);
  for (const auto& [id, n] : imu_counts) (*e.mutable_imu_samples())[id] = n;
  e.set_audio_chunks(sound.audio.size());
  e.set_audio_frames(audio_frames);
  e.set_sync_events(sync_events);
  session.chunks.push_back(std::move(end));
  return session;
}

}  // namespace posefuse::bench
