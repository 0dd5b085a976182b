#include "table1_session.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <string>

#include <opencv2/core.hpp>

#include "body/pose_parameters.hpp"
#include "body/smpl_model.hpp"
#include "forearm/synthetic_images.hpp"
#include "session/image_codec.hpp"
#include "session/sim_session_parts.hpp"
#include "session/stages/forearm_options.hpp"
#include "session/text_fields.hpp"
#include "sim/body_imu.hpp"
#include "sim/camera_session.hpp"
#include "sim/imu_device.hpp"
#include "sim/room_frame.hpp"
#include "sim/skeleton_pose.hpp"
#include "sim/sync_signals.hpp"

namespace posefuse::bench {

namespace {

using namespace session::testing;

using geometry::Quat;
using geometry::Vec3;

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
  const sim::ImuDeviceResult arm_imu =
      sim::simulate_imu_device(sim::SensorKinematics(sim::forearm_imu_trajectory(motion, rest, o.strap, W_from_R)),
                               arm_device, imu_options(o.seed + 2), 0.0, duration_s);

  std::vector<TimedChunk> timed;
  SimChunkCounts counts;
  add_imu_chunks(base_imu, base_device.clock, timed, counts);
  add_imu_chunks(arm_imu, arm_device.clock, timed, counts);
  // Sync (paper 1, II-G): the buzzer stops at 1.2 s camera time; BLE broadcasts from 0.5 s.
  const std::uint32_t audio_rate_hz = add_sync_chunks(base_device, arm_device, 1.2, true, o.seed + 3, timed, counts);

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
    // The upper arm is in the depth image too (a cylinder from the SMPL shoulder to the elbow).
    scene.shoulder_K = shot.truth[f].smpl_joints_K.col(truth.side == sim::BodySide::kRight ? body::kRightShoulder
                                                                                           : body::kLeftShoulder);
    const forearm::testing::ForearmImages images =
        forearm::testing::render_forearm(scene, cameras, 6.0, 0.002, o.seed * 100000 + f);
    v1::SessionChunk depth, color;
    *depth.mutable_depth() = session::encode_depth(cv::Mat(cameras.depth.height, cameras.depth.width, CV_16UC1,
                                                           const_cast<std::uint16_t*>(images.depth_mm.data())),
                                                   v1::DepthFrame::PNG16, t_us);
    *color.mutable_color() = session::encode_color_png(
        cv::Mat(cameras.color.height, cameras.color.width, CV_8UC1, const_cast<std::uint8_t*>(images.gray.data())),
        t_us);
    timed.push_back({t_s, std::move(depth)});
    timed.push_back({t_s + 1e-6, std::move(color)});
    // shot.chunks per frame: depth, body index, skeleton; only the skeleton is used (see the header).
    v1::SessionChunk skeleton = shot.chunks[3 * f + 2];
    timed.push_back({t_s + 2e-6, std::move(skeleton)});
  }
  v1::SessionChunk header;
  v1::SessionHeader& h = *header.mutable_header();
  h = shot.header;
  h.set_subject_id("table1");
  set_forearm_header(arm_device.device_id, base_device.device_id, cameras, audio_rate_hz, h);
  (*h.mutable_options())[session::kForearmKFromBKey] = quat_option(mount.K_from_B);
  (*h.mutable_options())[session::kForearmCalibrationSKey] = session::format_double(o.calibration_end_s);
  session.chunks = assemble_session(std::move(header), std::move(timed), frames, counts);
  return session;
}

}  // namespace posefuse::bench
