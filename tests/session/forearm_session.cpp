#include "forearm_session.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>

#include <opencv2/core.hpp>

#include "../forearm/synthetic_images.hpp"
#include "forearm/forearm_orientation.hpp"
#include "forearm/orientation_uncertainty.hpp"
#include "geometry/rotation_matrix.hpp"
#include "session/image_codec.hpp"
#include "session/text_fields.hpp"
#include "sim/imu_device.hpp"
#include "sim/scripted_motion.hpp"
#include "sim/sync_signals.hpp"
#include "sim_session_parts.hpp"

namespace posefuse::session::testing {

namespace {

using forearm::Quat;
using forearm::Vec3;
using std::numbers::pi;

double smooth_ramp(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * x * (10.0 + x * (-15.0 + 6.0 * x));
}

// After the hold: a smooth start into sinusoids on four joints.
sim::ScriptedMotion arm_motion(const ForearmSessionOptions& o) {
  sim::ScriptedMotion m;
  m.duration_s = o.duration_s;
  const double hold = o.hold_s, before = o.motion_before_hold_s;
  m.angles = [hold, before, extension = o.elbow_extension_rad](double t) {
    sim::ArmAngles a = sim::calibration_pose_angles();
    a.elbow_flexion_rad -= extension;
    const bool first_motion = before > 0.0 && t < before;
    const double u = first_motion ? t : t - before - hold;
    const double s = first_motion ? smooth_ramp(t / 1.0) * smooth_ramp((before - t) / 1.0) : smooth_ramp(u / 1.0);
    a.shoulder_abduction_rad += s * -0.5 * std::sin(2 * pi * 0.35 * u);
    a.shoulder_flexion_rad += s * 0.4 * std::sin(2 * pi * 0.3 * u);
    a.elbow_flexion_rad += s * 0.6 * std::sin(2 * pi * 0.45 * u);
    a.supination_rad += s * 0.8 * std::sin(2 * pi * 0.5 * u);
    return a;
  };
  return m;
}

// Camera 2 m in front of the subject (who faces +x_W), 1.2 m high, looking back along -x_W:
// x_K = -y_W (the camera's left), y_K = z_W (up), z_K = -x_W (forward).
struct CameraPose {
  Quat K_from_W;
  Vec3 centre_W;
  Vec3 to_K(const Vec3& p_W) const { return K_from_W * (p_W - centre_W); }
};
CameraPose camera_pose() {
  geometry::Mat3 R;
  R << 0, -1, 0, 0, 0, 1, -1, 0, 0;
  return {geometry::quat_from_rotation_matrix(R), Vec3(2.0, -0.3, 1.2)};
}

void set_vec(const Vec3& v, v1::Vec3* out) {
  out->set_x(v.x());
  out->set_y(v.y());
  out->set_z(v.z());
}

sim::ImuDeviceOptions imu_options(std::uint64_t seed) {
  sim::ImuDeviceOptions o;
  o.synth.error_model = sim::ImuErrorModel::none();
  o.synth.error_model.gyr_noise_density_rad_s_sqrt_hz = 2.5e-4;
  o.synth.error_model.acc_noise_density_m_s2_sqrt_hz = 1.5e-3;
  o.synth.error_model.mag_noise_uT = 0.3;
  o.synth.seed = seed;
  o.packet_loss.loss_rate = 0.0;
  return o;
}

}  // namespace

std::vector<v1::SessionChunk> make_forearm_session(const ForearmSessionOptions& o, ForearmSessionTruth* truth) {
  const CameraPose camera = camera_pose();
  sim::ArmGeometry arm;
  arm.F_from_A = geometry::quat_from_rotation_vector(Vec3(0.2, -0.1, 0.3));
  const double d_sw = 0.05;
  const sim::ScriptedMotion motion = arm_motion(o);

  // Devices on their own clocks; the base IMU sits still on the camera.
  const sim::SimDevice arm_device{"arm_r", sim::DeviceClock{3.2, o.arm_clock_drift}};
  const sim::SimDevice base_device{"base", sim::DeviceClock{-1.7, -20e-6}};
  const Quat K_from_B = geometry::quat_from_rotation_vector(Vec3(0.1, 2.0, -0.2));
  const Quat W_from_B = camera.K_from_W.conjugate() * K_from_B;
  sim::SensorTrajectory base_trajectory;
  base_trajectory.t0_s = -0.01;
  base_trajectory.dt_s = 1e-3;
  const std::size_t base_poses = static_cast<std::size_t>(std::ceil((o.duration_s + 0.02) / 1e-3)) + 1;
  base_trajectory.p_W_m.assign(base_poses, camera.centre_W + Vec3(0, 0, 0.1));
  base_trajectory.W_from_A.assign(base_poses, W_from_B);
  const sim::ImuDeviceResult base_imu = sim::simulate_imu_device(sim::SensorKinematics(base_trajectory), base_device,
                                                                 imu_options(o.seed + 1), 0.0, o.duration_s);
  sim::ImuDeviceResult arm_imu = sim::simulate_imu_device(sim::SensorKinematics(sim::imu_trajectory(arm, motion)),
                                                          arm_device, imu_options(o.seed + 2), 0.0, o.duration_s);
  if (o.arm_imu_lost_s > 0.0) {
    for (v1::ImuBatch& batch : arm_imu.batches) {
      v1::ImuBatch kept = batch;
      kept.clear_t_us();
      kept.clear_gyr_rad_s();
      kept.clear_acc_m_s2();
      kept.clear_mag_ut();
      for (int i = 0; i < batch.t_us_size(); ++i) {
        const double t_camera_s = arm_device.clock.to_camera_s(batch.t_us(i));
        if (t_camera_s >= o.arm_imu_lost_from_s && t_camera_s < o.arm_imu_lost_from_s + o.arm_imu_lost_s) continue;
        kept.add_t_us(batch.t_us(i));
        for (int k = 0; k < 3; ++k) {
          kept.add_gyr_rad_s(batch.gyr_rad_s(3 * i + k));
          kept.add_acc_m_s2(batch.acc_m_s2(3 * i + k));
          if (batch.mag_ut_size() > 0) kept.add_mag_ut(batch.mag_ut(3 * i + k));
        }
      }
      batch = std::move(kept);
    }
    std::erase_if(arm_imu.batches, [](const v1::ImuBatch& b) { return b.t_us_size() == 0; });
  }

  std::vector<TimedChunk> timed;
  SimChunkCounts counts;
  add_imu_chunks(base_imu, base_device.clock, timed, counts);
  add_imu_chunks(arm_imu, arm_device.clock, timed, counts);
  // Sync: the buzzer stops at 1.2 s camera time; broadcasts from 0.5 s.
  sim::BleBroadcastOptions ble;
  ble.repeat_every_s = o.ble_repeat_s;
  ble.repeat_until_s = o.duration_s;
  const std::uint32_t audio_rate_hz =
      add_sync_chunks(base_device, arm_device, 1.2, o.buzzer, o.seed + 3, timed, counts, ble, o.buzzer_tone_hz);

  // Camera frames at 30 Hz.
  const forearm::StrapCameras cameras = [] {
    forearm::StrapCameras c;
    c.depth = {200, 166, 143.0, 143.0, 100.0, 83.0, 0.02, -0.05, 0.0, 0.0, 0.0};
    c.color = {480, 270, 400.0, 400.0, 240.0, 135.0, 0.03, -0.04, 0.0, 0.0, 0.0};
    c.color_from_depth = Quat(Eigen::AngleAxisd(1.0 * pi / 180.0, Vec3::UnitY()));
    c.color_from_depth_m = Vec3(-0.052, 0.0, 0.0);
    return c;
  }();
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const auto noisy = [&](const Vec3& p) {
    return Vec3(p + o.joint_noise_m * Vec3(normal(rng), normal(rng), normal(rng)));
  };
  const Vec3 shoulder_K = camera.to_K(arm.shoulder_p_W_m);
  std::uint64_t frames = 0;
  *truth = ForearmSessionTruth{};
  truth->K_from_W = camera.K_from_W;
  truth->device_us_at_camera_zero = {{arm_device.device_id, arm_device.clock.to_device_us(0.0)},
                                     {base_device.device_id, base_device.clock.to_device_us(0.0)}};
  truth->device_drift = {{arm_device.device_id, arm_device.clock.drift},
                         {base_device.device_id, base_device.clock.drift}};
  truth->model = {arm.strap_radius_m, arm.strap_to_elbow_m, d_sw, arm.upper_arm_m, arm.F_from_A};
  truth->K_from_F_calibration = camera.K_from_W * sim::arm_pose(arm, sim::calibration_pose_angles()).W_from_F;
  for (int k = 0;; ++k) {
    const double t = k / 30.0;
    if (t > o.duration_s) break;
    const std::int64_t t_us = std::llround(t * 1e6);
    const sim::ArmAngles angles = motion.angles(t);
    const sim::ArmPose pose = sim::arm_pose(arm, angles);
    const Quat K_from_F = camera.K_from_W * pose.W_from_F;
    const Vec3 elbow_K = camera.to_K(pose.elbow_p_W_m);
    const Vec3 wrist_K = elbow_K + K_from_F * Vec3(0, arm.strap_to_elbow_m + d_sw, 0);
    const bool occluded = t >= o.occlusion_begin_s && t < o.occlusion_end_s;
    truth->frame_t_us.push_back(t_us);
    truth->imu_K.push_back(camera.to_K(pose.imu_p_W_m));
    truth->K_from_F.push_back(K_from_F);
    truth->supination_rad.push_back(angles.supination_rad);

    forearm::testing::ForearmScene scene;
    scene.elbow_K = elbow_K;
    scene.wrist_K = wrist_K;
    scene.radius_m = arm.strap_radius_m;
    scene.strap_to_elbow_m = arm.strap_to_elbow_m;
    scene.strap_visible = o.strap_drawn && !occluded;
    if (o.upper_arm_drawn) scene.shoulder_K = shoulder_K;
    const forearm::testing::ForearmImages images =
        forearm::testing::render_forearm(scene, cameras, 6.0, 0.002, o.seed * 1000 + static_cast<std::uint64_t>(k));
    v1::SessionChunk depth;
    *depth.mutable_depth() = encode_depth(cv::Mat(cameras.depth.height, cameras.depth.width, CV_16UC1,
                                                  const_cast<std::uint16_t*>(images.depth_mm.data())),
                                          v1::DepthFrame::PNG16, t_us);
    v1::SessionChunk color;
    *color.mutable_color() = encode_color_png(
        cv::Mat(cameras.color.height, cameras.color.width, CV_8UC1, const_cast<std::uint8_t*>(images.gray.data())),
        t_us);
    v1::SessionChunk skeleton;
    v1::SkeletonFrame& s = *skeleton.mutable_skeleton();
    s.set_t_us(t_us);
    s.set_body_id(0);
    for (int j = 0; j < 25; ++j) {
      v1::SkeletonJoint& joint = *s.add_joints();
      Vec3 p = shoulder_K + Vec3(0.3, -0.4, 0.0);  // joints the stage does not read
      auto state = v1::SkeletonJoint::TRACKED;
      if (j == 8) p = noisy(shoulder_K + o.shoulder_bias_m);
      if (j == 9) p = noisy(elbow_K + o.elbow_bias_m);
      if (j == 10) p = noisy(wrist_K + o.wrist_bias_m);
      if ((j == 9 || j == 10) && occluded) state = v1::SkeletonJoint::INFERRED;
      set_vec(p, joint.mutable_position_m());
      joint.set_state(state);
    }
    timed.push_back({t, depth});
    timed.push_back({t + 1e-6, color});
    timed.push_back({t + 2e-6, skeleton});
    ++frames;
  }
  v1::SessionChunk header;
  v1::SessionHeader& h = *header.mutable_header();
  h.set_format_version(1);
  h.set_subject_id("forearm-test");
  set_forearm_header("arm_r", "base", cameras, audio_rate_hz, h);
  if (o.camera_alignment) {
    std::ostringstream q;
    q.precision(17);
    q << K_from_B.w() << ' ' << K_from_B.x() << ' ' << K_from_B.y() << ' ' << K_from_B.z();
    (*h.mutable_options())["forearm.K_from_B"] = q.str();
  }
  (*h.mutable_options())["forearm.calibration_s"] = format_double(o.calibration_s);
  (*h.mutable_options())["forearm.axis"] = o.axis;
  (*h.mutable_options())["forearm.upper_arm"] = o.upper_arm;
  (*h.mutable_options())["fit.enabled"] = o.body_fit ? "true" : "false";
  if (!o.buzzer_hz_option.empty()) (*h.mutable_options())["forearm.buzzer_hz"] = o.buzzer_hz_option;
  return assemble_session(std::move(header), std::move(timed), frames, counts);
}

namespace {

// The truth frame within 2 ms of t_us, or npos.
std::size_t frame_near(const ForearmSessionTruth& truth, std::int64_t t_us) {
  const auto it = std::lower_bound(truth.frame_t_us.begin(), truth.frame_t_us.end(), t_us - 2000);
  if (it == truth.frame_t_us.end() || std::abs(*it - t_us) > 2000) return static_cast<std::size_t>(-1);
  return static_cast<std::size_t>(it - truth.frame_t_us.begin());
}

Vec3 vec(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

ForearmSessionErrors evaluate_forearm_results(const ForearmSessionTruth& truth,
                                              const std::vector<v1::FitResult>& results, bool offline_solution) {
  constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  ForearmSessionErrors e;
  double orientation_sq = 0.0, visible_sq = 0.0;
  std::map<int, double> recovered_sq;
  for (const v1::FitResult& result : results) {
    if (result.has_forearm_orientations()) {
      const v1::ForearmOrientationBatch& b = result.forearm_orientations();
      if (b.offline() != offline_solution) continue;
      for (int i = 0; i < b.t_us_size() && 4 * i + 3 < b.k_from_f_size() && i < b.pronation_rad_size(); ++i) {
        const std::size_t k = frame_near(truth, b.t_us(i));
        if (k == kNone) continue;
        const Quat K_from_F(b.k_from_f(4 * i), b.k_from_f(4 * i + 1), b.k_from_f(4 * i + 2), b.k_from_f(4 * i + 3));
        const double angle = geometry::angle_between(K_from_F, truth.K_from_F[k]);
        orientation_sq += angle * angle;
        e.orientation_max_rad = std::max(e.orientation_max_rad, angle);
        const double true_pronation =
            forearm::pronation_angle(truth.K_from_F_calibration, truth.K_from_F[k], forearm::Side::kRight);
        if (std::isnan(b.pronation_rad(i))) {
          ++e.pronation_nan;
        } else {
          e.pronation_max_rad = std::max(e.pronation_max_rad, std::abs(b.pronation_rad(i) - true_pronation));
        }
        if (i < b.confidence_size() && b.confidence(i) >= 0.5) {
          ++e.confident_samples;
          e.confident_beyond_15_deg += angle > forearm::kConfidentErrorBoundRad;
          e.confident_max_rad = std::max(e.confident_max_rad, angle);
        }
        if (i < b.uncertainty_rad_size() && angle <= forearm::kBound99OverRms * b.uncertainty_rad(i)) {
          ++e.within_predicted_bound;
        }
        ++e.orientation_samples;
      }
    } else if (result.has_frame()) {
      const std::size_t k = frame_near(truth, result.frame().t_us());
      if (k == kNone) continue;
      ++e.frames;
      for (const v1::ImuPosition& p : result.frame().imu_positions()) {
        const double error = (vec(p.position_m()) - truth.imu_K[k]).norm();
        if (p.source() == v1::VISUAL) {
          visible_sq += error * error;
          ++e.visible_frames;
        } else if (p.source() == v1::PREDICTED) {
          e.predicted_max_m = std::max(e.predicted_max_m, error);
          ++e.predicted_frames;
        }
      }
    } else if (result.has_recovered_segment()) {
      const v1::RecoveredSegment& s = result.recovered_segment();
      ++e.segments;
      ForearmSessionErrors::Recovered& r = e.recovered[s.method()];
      for (const auto& sample : s.samples()) {
        const std::size_t k = frame_near(truth, sample.t_us());
        if (k == kNone) continue;
        const double error = (vec(sample.imu_m()) - truth.imu_K[k]).norm();
        recovered_sq[s.method()] += error * error;
        r.max_m = std::max(r.max_m, error);
        ++r.samples;
      }
    }
  }
  if (e.orientation_samples > 0) e.orientation_rms_rad = std::sqrt(orientation_sq / e.orientation_samples);
  if (e.visible_frames > 0) e.visible_rms_m = std::sqrt(visible_sq / e.visible_frames);
  for (auto& [method, r] : e.recovered) {
    if (r.samples > 0) r.rms_m = std::sqrt(recovered_sq[method] / r.samples);
  }
  return e;
}

}  // namespace posefuse::session::testing
