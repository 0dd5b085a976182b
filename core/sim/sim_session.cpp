#include "sim/sim_session.hpp"

#include <time.h>
#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <opencv2/core.hpp>

#include "body/body_evaluator.hpp"
#include "body/standing_height.hpp"
#include "common/error.hpp"
#include "raycast/mesh_scene.hpp"
#include "session/chunk_order.hpp"
#include "session/image_codec.hpp"
#include "session/mag_calibration_option.hpp"
#include "session/session_validator.hpp"
#include "session/stages/forearm_options.hpp"
#include "session/text_fields.hpp"
#include "sim/forearm_strap.hpp"
#include "sim/mag_precalibration.hpp"
#include "sim/option_checks.hpp"
#include "sim/ordered_workers.hpp"
#include "sim/room_frame.hpp"
#include "sim/sim_rng.hpp"
#include "sim/skeleton_pose.hpp"

namespace posefuse::sim {
namespace {

using std::numbers::pi;
constexpr int kFramesAheadPerWorker = 2;  // frames a worker may finish before they are written
// zstd level of depth chunks: level 3 took a fifth of a frame's CPU on noisy depth; level 1 is
// ~2.5 times faster for 14 % larger depth payloads, 11 % larger sessions (docs/simulator.md,
// "Speed").
constexpr int kDepthZstdLevel = 1;

// Body index chunks go with the depth encoding: PNG8 beside PNG16 (a recording directory
// stores both as is), else ZSTD_U8, which the server decodes about 30 times faster than PNG8.
v1::BodyIndexFrame::Encoding body_index_encoding(v1::DepthFrame::Encoding depth_encoding) {
  return depth_encoding == v1::DepthFrame::PNG16 ? v1::BodyIndexFrame::PNG8 : v1::BodyIndexFrame::ZSTD_U8;
}
using Mat3 = Eigen::Matrix3d;

double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// Adds the calling thread's CPU time since the last lap to `times[part]`.
class CpuLap {
 public:
  explicit CpuLap(SimTimings& times) : times_(times), last_(thread_cpu_s()) {}
  void operator()(const char* part) {
    const double now = thread_cpu_s();
    times_[part] += now - last_;
    last_ = now;
  }

 private:
  SimTimings& times_;
  double last_;
};

const std::array<const char*, 2> kArmDeviceIds = {"imu_left", "imu_right"};
const char* const kBaseDeviceId = "imu_base";
const std::array<int, 2> kElbow = {body::kLeftElbow, body::kRightElbow};
const std::array<int, 2> kWrist = {body::kLeftWrist, body::kRightWrist};
const std::array<int, 2> kShoulder = {body::kLeftShoulder, body::kRightShoulder};

BodySide side_of(int arm) { return arm == 0 ? BodySide::kLeft : BodySide::kRight; }

// Pronation: the elbow's twist relative to the upper arm about y_F (swing-twist), relative to
// the rest pose; + pronation.
double pronation_rad(const SkeletonPose& pose, int arm, const Quat& rest_R_from_F) {
  const auto a = static_cast<std::size_t>(arm);
  const Mat3& R_elbow = pose.rotation[static_cast<std::size_t>(kElbow[a])];
  const Mat3& R_shoulder = pose.rotation[static_cast<std::size_t>(kShoulder[a])];
  const Mat3 rest_F = rest_R_from_F.toRotationMatrix();
  const Quat local(rest_F.transpose() * R_shoulder.transpose() * R_elbow * rest_F);
  const double wrapped = std::remainder(2.0 * std::atan2(local.y(), local.w()), 2 * pi);
  return arm == 1 ? -wrapped : wrapped;  // + about y_F supinates the right arm
}

// The forearm frame F of one arm of a posed skeleton (forearm_strap.hpp) in K, and its pronation.
struct ForearmAt {
  Quat K_from_F = Quat::Identity();
  Vec3 strap_p_K = Vec3::Zero();
  double pronation_rad = 0.0;
};

ForearmAt forearm_at(const SkeletonPose& pose, int arm, const std::array<ForearmStrap, 2>& straps,
                     const std::array<Quat, 2>& rest_R_from_F, const Eigen::Isometry3d& K_from_Body) {
  const auto a = static_cast<std::size_t>(arm);
  const ForearmPose forearm = forearm_pose(pose, rest_R_from_F[a], straps[a]);
  ForearmAt out;
  out.K_from_F = (Quat(K_from_Body.linear()) * forearm.R_from_F).normalized();
  out.strap_p_K = K_from_Body * forearm.strap_R_m;
  out.pronation_rad = pronation_rad(pose, arm, rest_R_from_F[a]);
  return out;
}

Quat random_rotation(SimRng& rng, double sigma) {
  const Vec3 v(sigma * rng.normal(), sigma * rng.normal(), sigma * rng.normal());
  return geometry::quat_from_rotation_vector(v);
}

// A smooth bounded signal: three sinusoids with random phases and weights summing to one.
class SlowWave {
 public:
  SlowWave(SimRng& rng, double amplitude, double period_s) : amplitude_(amplitude) {
    double total = 0;
    for (int k = 0; k < 3; ++k) {
      weight_[k] = 0.2 + rng.uniform();
      total += weight_[k];
      phase_[k] = 2 * pi * rng.uniform();
      omega_[k] = 2 * pi * (k + 1) / period_s;
    }
    for (double& w : weight_) w /= total;
  }
  double operator()(double t) const {
    double sum = 0;
    for (int k = 0; k < 3; ++k) sum += weight_[k] * std::sin(omega_[k] * t + phase_[k]);
    return amplitude_ * sum;
  }

 private:
  double amplitude_;
  double weight_[3] = {}, phase_[3] = {}, omega_[3] = {};
};

struct FramePlan {
  std::int64_t index = 0;
  double t_s = 0;
  std::int64_t t_us = 0;
};

struct FrameOutput {
  std::vector<v1::SessionChunk> chunks;
  SimFrameTruth truth;
};

// Everything one thread needs to turn a pose into a frame's chunks and truth.
class FrameWorker {
 public:
  FrameWorker(const SimSessionOptions& options, const RenderModel& render, const body::PoseLayout& layout,
              const raycast::DepthCamera& camera, const CameraSkeletonSimulator& skeleton, const StrapPlacement& straps,
              const std::array<ForearmStrap, 2>& forearm_straps, const std::array<Quat, 2>& rest_R_from_F,
              const Eigen::Isometry3d& K_from_Body, const std::vector<RoomPlane>& room,
              const StaticBackground& background, const std::vector<Eigen::Matrix3Xd>& wobble)
      : options_(options),
        render_(render),
        evaluator_(render.model, layout),
        scene_(raycast::EmbreeDevice::shared(), render.model->faces, render.model->num_vertices()),
        camera_(camera),
        skeleton_(skeleton),
        straps_(straps),
        forearm_straps_(forearm_straps),
        rest_R_from_F_(rest_R_from_F),
        K_from_Body_(K_from_Body),
        background_(background),
        wobble_(wobble),
        soft_tissue_(render.model->weights, render.surface_vertices) {
    if (options.color)
      color_ = std::make_unique<ColorRenderer>(options.color_camera, render, straps, room, options.seed);
  }

  FrameOutput process(const FramePlan& plan, const BodyMotion& motion) {
    CpuLap lap(times_);
    const Eigen::VectorXd theta = motion.poses(plan.t_s);
    if (theta.size() != evaluator_.layout().size() || !theta.allFinite()) {
      throw_invalid("motion", "frame " + std::to_string(plan.index) + " gave a bad pose");
    }
    evaluator_.evaluate(options_.betas, theta, body::Derivatives::kNone);
    Eigen::Matrix3Xd vertices_K = K_from_Body_ * evaluator_.vertices();
    lap("depth: pose, skin, ray cast");
    soft_tissue_.apply(wobble_[static_cast<std::size_t>(plan.index)], K_from_Body_.linear(), vertices_K);
    lap("depth: soft-tissue wobble");
    scene_.update_vertices(vertices_K);
    scene_.render(camera_, 0, images_);
    lap("depth: pose, skin, ray cast");
    FrameOutput out;
    out.truth = frame_truth(plan);  // from the clean render, before the room is added
    lap("truth per frame");
    background_.composite(images_.depth_mm);
    const NoisyDepth noisy = apply_depth_noise(camera_, images_.depth_mm, images_.body_index, options_.depth_noise,
                                               options_.seed, plan.index, &background_);
    lap("depth: room, sensor errors");
    const SmplJointsK joints = smpl_joints_in_camera(evaluator_, K_from_Body_);
    const cv::Mat depth(camera_.height(), camera_.width(), CV_16UC1, const_cast<std::uint16_t*>(noisy.depth_mm.data()));
    const cv::Mat body_index(camera_.height(), camera_.width(), CV_8UC1,
                             const_cast<std::uint8_t*>(noisy.body_index.data()));
    out.chunks.emplace_back().mutable_depth()->CopyFrom(
        session::encode_depth(depth, options_.depth_encoding, plan.t_us, kDepthZstdLevel));
    out.chunks.emplace_back().mutable_body_index()->CopyFrom(session::encode_body_index(
        body_index, body_index_encoding(options_.depth_encoding), plan.t_us, kDepthZstdLevel));
    lap("depth, body index: encode (zstd or PNG)");
    out.chunks.emplace_back().mutable_skeleton()->CopyFrom(
        skeleton_.simulate(joints, noisy.depth_mm, images_.face, plan.index, plan.t_us, 0));
    lap("skeleton");
    if (color_) {
      const cv::Mat bgr = color_->render(vertices_K, plan.index);
      lap("color: ray cast, shade, noise");
      out.chunks.emplace_back().mutable_color()->CopyFrom(
          encode_color_frame(bgr, options_.color_camera.jpeg_quality, plan.t_us));
      lap("color: encode (JPEG)");
    }
    out.truth.smpl_joints_K = joints.positions_K;
    out.truth.camera_joints_K = camera_joints_from_smpl(joints);
    lap("truth per frame");
    return out;
  }

  const SimTimings& times() const { return times_; }

 private:
  SimFrameTruth frame_truth(const FramePlan& plan) const {
    SimFrameTruth truth;
    truth.t_us = plan.t_us;
    const SkeletonPose pose = skeleton_pose_of(evaluator_);
    for (int arm = 0; arm < 2; ++arm) {
      const auto a = static_cast<std::size_t>(arm);
      const Eigen::Vector3d elbow = evaluator_.joints().col(kElbow[a]);
      const Eigen::Vector3d wrist = evaluator_.joints().col(kWrist[a]);
      const ForearmAt forearm = forearm_at(pose, arm, forearm_straps_, rest_R_from_F_, K_from_Body_);
      truth.K_from_F[a] = forearm.K_from_F;
      truth.strap_p_K[a] = forearm.strap_p_K;
      truth.pronation_rad[a] = forearm.pronation_rad;
      int visible = 0;
      for (int k = 1; k <= 5; ++k) {
        const Eigen::Vector3d p = K_from_Body_ * (elbow + (wrist - elbow) * (k - 0.5) / 5.0);
        const int face = face_at(p);
        if (face >= 0 && render_.forearm_arm[static_cast<std::size_t>(render_.model->faces(0, face))] == arm) {
          ++visible;
        }
      }
      truth.forearm_visible_fraction[a] = visible / 5.0;
      const auto pixel = pixel_of(truth.strap_p_K[a]);
      truth.strap_visible[a] =
          pixel >= 0 && images_.face[static_cast<std::size_t>(pixel)] >= 0 &&
          is_strap(render_, straps_, options_.color_camera.strap_width_m, images_.face[static_cast<std::size_t>(pixel)],
                   images_.u[static_cast<std::size_t>(pixel)], images_.v[static_cast<std::size_t>(pixel)]);
    }
    return truth;
  }

  std::int64_t pixel_of(const Eigen::Vector3d& p_K) const {
    const auto uv = camera_.project(p_K);
    if (!uv) return -1;
    const long col = std::lround((*uv)[0]), row = std::lround((*uv)[1]);
    if (col < 0 || row < 0 || col >= camera_.width() || row >= camera_.height()) return -1;
    return row * camera_.width() + col;
  }
  int face_at(const Eigen::Vector3d& p_K) const {
    const std::int64_t pixel = pixel_of(p_K);
    return pixel < 0 ? -1 : images_.face[static_cast<std::size_t>(pixel)];
  }

  const SimSessionOptions& options_;
  const RenderModel& render_;
  body::BodyEvaluator evaluator_;
  raycast::MeshScene scene_;
  const raycast::DepthCamera& camera_;
  const CameraSkeletonSimulator& skeleton_;
  StrapPlacement straps_;
  std::array<ForearmStrap, 2> forearm_straps_;
  std::array<Quat, 2> rest_R_from_F_;
  Eigen::Isometry3d K_from_Body_;
  const StaticBackground& background_;
  const std::vector<Eigen::Matrix3Xd>& wobble_;  // per frame, Body frame (soft_tissue.hpp)
  SoftTissueSkin soft_tissue_;
  std::unique_ptr<ColorRenderer> color_;
  raycast::RenderImages images_;
  SimTimings times_;
};

MotionContext motion_context(const SimSessionOptions& options) {
  MotionContext context;
  context.sex = options.sex;
  context.betas = options.betas;
  return context;
}

SimSessionOptions with_motion_duration(SimSessionOptions options, const BodyMotion& motion) {
  if (!options.duration_from_motion) return options;
  options.duration_from_motion = false;
  options.duration_s = motion.duration_s;
  if (!(motion.duration_s >= 1.0 && motion.duration_s <= 3600.0)) {
    throw_invalid("duration_s", "is 'clip': the motion lasts " + std::to_string(motion.duration_s) +
                                    " s, a session must last 1..3600 s");
  }
  return options;
}

// K_from_level: a level camera's frame turned by the options' pitch (about x, down for > 0) and
// then roll (about z).
Mat3 camera_tilt(const SimSessionOptions& options) {
  constexpr double kDeg = pi / 180.0;
  return (Eigen::AngleAxisd(options.camera_roll_deg * kDeg, Vec3::UnitZ()) *
          Eigen::AngleAxisd(-options.camera_pitch_deg * kDeg, Vec3::UnitX()))
      .toRotationMatrix();
}

}  // namespace

void validate(const SimSessionOptions& options) {
  if (!options.duration_from_motion) {
    require_finite(options.duration_s, "duration_s");
    if (options.duration_s < 1.0 || options.duration_s > 3600.0) {
      throw_invalid("duration_s", "is " + std::to_string(options.duration_s) + ", must be 1..3600 s");
    }
  }
  if (options.betas.size() > body::kTemplateNumBetas || !options.betas.allFinite()) {
    throw_invalid("betas", "must be at most 10 finite values");
  }
  require_finite(options.heading_rad, "heading_rad");
  raycast::validate(options.depth_intrinsics);
  require_positive(options.depth_rate_hz, "depth_rate_hz");
  require_positive(options.camera_height_m, "camera_height_m");
  require_positive(options.subject_distance_m, "subject_distance_m");
  if (!(std::abs(options.camera_pitch_deg) <= 30.0))
    throw_invalid("camera_pitch_deg", "is " + std::to_string(options.camera_pitch_deg) + ", must be in -30..30");
  if (!(std::abs(options.camera_roll_deg) <= 20.0))
    throw_invalid("camera_roll_deg", "is " + std::to_string(options.camera_roll_deg) + ", must be in -20..20");
  if (options.wall_distance_m <= options.subject_distance_m + 0.5) {
    throw_invalid("wall_distance_m",
                  "is " + std::to_string(options.wall_distance_m) + ", must be at least 0.5 m behind the subject");
  }
  validate(options.depth_noise);
  if (options.color) validate(options.color_camera);
  validate(options.clothing);
  validate(options.soft_tissue);
  require_positive(options.strap_to_elbow_m, "strap_to_elbow_m");
  require_positive(options.strap_radius_m, "strap_radius_m");
  require_non_negative(options.mount_sigma_rad, "mount_sigma_rad");
  require_non_negative(options.height_error_m, "height_error_m");
  if (options.height_error_m > 0.1) throw_invalid("height_error_m", "must be at most 0.1 m");
  require_non_negative(options.strap_slip.max_rotation_rad, "strap_slip.max_rotation_rad");
  require_non_negative(options.strap_slip.max_slide_m, "strap_slip.max_slide_m");
  require_positive(options.strap_slip.period_s, "strap_slip.period_s");
  require_positive(options.imu.rate_hz, "imu.rate_hz");
  if (options.clock_offset_max_s < 1.0 || !std::isfinite(options.clock_offset_max_s)) {
    throw_invalid("clock_offset_max_s", "must be >= 1 s");
  }
  if (!(options.clock_drift_max >= 0 && options.clock_drift_max < 1e-3)) {
    throw_invalid("clock_drift_max", "must be in [0, 1e-3)");
  }
  require_positive(options.buzzer_stop_s, "buzzer_stop_s");
  require_non_negative(options.buzzer_repeat_s, "buzzer_repeat_s");
  if (options.buzzer_repeat_s > 0 && options.buzzer_repeat_s < 2) throw_invalid("buzzer_repeat_s", "must be 0 or >= 2");
  if (options.depth_encoding != v1::DepthFrame::ZSTD_U16_LE && options.depth_encoding != v1::DepthFrame::PNG16) {
    throw_invalid("depth_encoding", "is " + std::to_string(options.depth_encoding) + ", must be ZSTD_U16_LE or PNG16");
  }
  if (options.threads < 1 || options.threads > 64) {
    throw_invalid("threads", "is " + std::to_string(options.threads) + ", must be 1..64");
  }
}

SimSessionOptions with_session_duration(const SimSessionOptions& options) {
  if (!options.duration_from_motion) return options;
  return with_motion_duration(options, select_motion(options.motion, options.motion_options, motion_context(options)));
}

SimTruth simulate_session(const SimSessionOptions& requested, session::ChunkSink& sink,
                          const std::function<void(const SimProgress&)>& progress) {
  validate(requested);
  const BodyMotion motion = select_motion(requested.motion, requested.motion_options, motion_context(requested));
  const SimSessionOptions options = with_motion_duration(requested, motion);
  SimTruth truth;
  truth.warnings = motion.warnings;
  CpuLap lap(truth.cpu_s);
  // Rest joints do not depend on the layout's DOFs (all zero).
  const body::PoseLayout rest_layout = body::PoseLayout::full_body();
  const auto fitted = body::make_template(options.sex);
  const RenderModel render = make_render_model(*fitted, options.betas, options.clothing, options.seed);
  truth.options = options;
  {
    body::BodyEvaluator rest(render.model, rest_layout);
    rest.evaluate(options.betas, rest_layout.zero(), body::Derivatives::kNone);
    truth.rest_joints = rest.rest_joints();
  }
  // Placement: the camera faces the subject (see camera_session.hpp), tilted by the options' pitch
  // and roll about itself; W shares Body's origin.
  truth.K_from_Body = Eigen::Isometry3d(camera_tilt(options)) *
                      Eigen::Translation3d(0, -options.camera_height_m, options.subject_distance_m) *
                      Eigen::AngleAxisd(pi, Eigen::Vector3d::UnitY());
  truth.W_from_Body = W_from_R(options.heading_rad);
  const Mat3 W_from_Body = truth.W_from_Body.toRotationMatrix();
  truth.K_from_W = Quat(truth.K_from_Body.linear() * W_from_Body.transpose()).normalized();
  truth.camera_p_W_m = W_from_Body * truth.K_from_Body.inverse().translation();
  const Eigen::Isometry3d& K_from_Body = truth.K_from_Body;
  const auto W_to_K = [&](const Vec3& p_W) -> Vec3 { return K_from_Body * (W_from_Body.transpose() * p_W); };
  // Exercises hold their rest pose after the end; a BVH clip would drift along its end tangents.
  if (options.motion == "bvh" && options.duration_s > motion.duration_s) {
    throw_invalid("duration_s", "is " + std::to_string(options.duration_s) + " s, the BVH clip lasts only " +
                                    std::to_string(motion.duration_s) +
                                    " s (duration_s = clip plays exactly the whole clip)");
  }
  const body::PoseLayout layout = body::PoseLayout::all_joints();

  // Arms: strap geometry and IMU mounting.
  SimRng mount_rng(options.seed, "imu_mount");
  StrapPlacement straps = {std::nan(""), std::nan("")};
  std::array<ForearmStrap, 2> forearm_straps;  // F on the posed body (forearm_strap.hpp); no IMU mounting
  std::array<Quat, 2> rest_R_from_F;
  for (int arm = 0; arm < 2; ++arm) {
    const auto a = static_cast<std::size_t>(arm);
    SimArmTruth& t = truth.arms[a];
    t.arm = arm;
    t.has_imu = options.arm_imu[a];
    t.device_id = kArmDeviceIds[a];
    t.r_m = options.strap_radius_m;
    t.d_se_m = options.strap_to_elbow_m;
    const double forearm = (truth.rest_joints.col(kWrist[a]) - truth.rest_joints.col(kElbow[a])).norm();
    t.d_sw_m = forearm - t.d_se_m;
    t.d_ul_m = (truth.rest_joints.col(kElbow[a]) - truth.rest_joints.col(kShoulder[a])).norm();
    if (t.d_sw_m <= 0.02) {
      throw_invalid("strap_to_elbow_m",
                    "is " + std::to_string(t.d_se_m) + ", the forearm is only " + std::to_string(forearm) + " m long");
    }
    t.F_from_A = random_rotation(mount_rng, options.mount_sigma_rad);
    if (t.has_imu) straps[a] = t.d_se_m;
    forearm_straps[a].side = side_of(arm);
    forearm_straps[a].strap_to_elbow_m = t.d_se_m;
    forearm_straps[a].strap_radius_m = 0.0;  // the strap centre on the forearm axis
    rest_R_from_F[a] = forearm_rest_R_from_F(truth.rest_joints, side_of(arm));
  }

  // Devices and clocks.
  std::vector<SimDevice> devices;
  for (int arm = 0; arm < 2; ++arm) {
    if (!truth.arms[static_cast<std::size_t>(arm)].has_imu) continue;
    devices.push_back(SimDevice{kArmDeviceIds[static_cast<std::size_t>(arm)], {}});
  }
  devices.push_back(SimDevice{kBaseDeviceId, {}});
  for (SimDevice& device : devices) {
    SimRng rng(options.seed, "clock/" + device.device_id);
    device.clock.offset_s = 1.0 + (options.clock_offset_max_s - 1.0) * rng.uniform();
    device.clock.drift = options.clock_drift_max * (2 * rng.uniform() - 1);
  }

  // Arm IMU trajectories at 1 kHz from the posed skeleton's forearms: mounting, radius, slip.
  const double dt = 1e-3;
  std::vector<SensorKinematics> kinematics;
  const auto grid_size = static_cast<std::size_t>(std::ceil(options.duration_s / dt - 1e-9)) + 5;
  for (int arm = 0; arm < 2; ++arm) {
    const auto a = static_cast<std::size_t>(arm);
    const SimArmTruth& t = truth.arms[a];
    if (!t.has_imu) continue;
    SimRng slip_rng(options.seed, std::string("strap_slip/") + kArmDeviceIds[a]);
    const double slip_scale = options.strap_slip.enabled ? 1.0 : 0.0;
    const SlowWave slip_turn(slip_rng, slip_scale * options.strap_slip.max_rotation_rad, options.strap_slip.period_s);
    const SlowWave slip_slide(slip_rng, slip_scale * options.strap_slip.max_slide_m, options.strap_slip.period_s);
    SensorTrajectory trajectory;
    trajectory.dt_s = dt;
    trajectory.t0_s = -2 * dt;
    for (std::size_t k = 0; k < grid_size; ++k) {
      const double time = trajectory.t0_s + static_cast<double>(k) * dt;
      const SkeletonPose pose = pose_skeleton(truth.rest_joints, layout, motion.poses(time));
      const ForearmPose forearm = forearm_pose(pose, rest_R_from_F[a], forearm_straps[a]);
      const Mat3 W_from_F = W_from_Body * forearm.R_from_F.toRotationMatrix();
      const Vec3 strap_W = W_from_Body * forearm.strap_R_m;
      const Mat3 slipped = W_from_F * Eigen::AngleAxisd(slip_turn(time), Vec3::UnitY()).toRotationMatrix();
      const Vec3 strap_slid = strap_W + W_from_F * Vec3(0, slip_slide(time), 0);
      trajectory.p_W_m.push_back(strap_slid + slipped * Vec3(t.r_m, 0, 0));
      trajectory.W_from_A.push_back(Quat(slipped * t.F_from_A.toRotationMatrix()).normalized());
    }
    kinematics.emplace_back(std::move(trajectory));
  }
  // The base IMU: B's x along K's z, y along K's x, z along K's y (level camera: B ~ W up to
  // heading), with a small mounting error.
  {
    Mat3 K_from_B_nominal;
    K_from_B_nominal << 0, 1, 0, 0, 0, 1, 1, 0, 0;
    SimRng rng(options.seed, "base_mount");
    truth.K_from_B = (Quat(K_from_B_nominal) * random_rotation(rng, 0.02)).normalized();
    const Quat W_from_B = (Quat(W_from_Body) * Quat(K_from_Body.linear()).conjugate() * truth.K_from_B).normalized();
    SensorTrajectory still;
    still.dt_s = 0.01;
    still.t0_s = -0.02;
    const auto n = static_cast<std::size_t>(std::ceil(options.duration_s / still.dt_s - 1e-9)) + 5;
    still.p_W_m.assign(n, truth.camera_p_W_m);
    still.W_from_A.assign(n, W_from_B);
    kinematics.emplace_back(std::move(still));
  }

  lap("setup: render model, IMU pose trajectories");
  std::vector<v1::SessionChunk> small;  // IMU, audio and sync chunks, merged in later
  for (std::size_t d = 0; d < devices.size(); ++d) {
    ImuDeviceOptions imu = options.imu;
    SimRng seed_rng(options.seed, "imu_seed/" + devices[d].device_id);
    imu.synth.seed = static_cast<std::uint64_t>(seed_rng.uniform() * 0x1.0p53);
    const ImuDeviceResult result = simulate_imu_device(kinematics[d], devices[d], imu, 0.0, options.duration_s);
    SimDeviceTruth device;
    device.device_id = devices[d].device_id;
    device.role = d + 1 == devices.size()                ? v1::ImuDevice::BASE
                  : device.device_id == kArmDeviceIds[0] ? v1::ImuDevice::ARM_LEFT
                                                         : v1::ImuDevice::ARM_RIGHT;
    device.clock = devices[d].clock;
    device.errors = result.truth.errors;
    device.t_device_us = result.ticks.t_device_us;
    device.t_camera_s = result.ticks.t_camera_s;
    device.lost = result.lost;
    device.W_from_A = result.truth.W_from_A;
    device.gyr_bias_rad_s = result.truth.gyr_bias_rad_s;
    if (device.role != v1::ImuDevice::BASE) {
      // The forearm under the strap at every sample's true camera time (no slip: the bone).
      const int arm = device.role == v1::ImuDevice::ARM_LEFT ? 0 : 1;
      for (const double t_camera_s : device.t_camera_s) {
        const double t = std::clamp(t_camera_s, 0.0, options.duration_s);
        const SkeletonPose pose = pose_skeleton(truth.rest_joints, layout, motion.poses(t));
        const ForearmAt forearm = forearm_at(pose, arm, forearm_straps, rest_R_from_F, K_from_Body);
        device.K_from_F.push_back(forearm.K_from_F);
        device.pronation_rad.push_back(forearm.pronation_rad);
      }
    }
    truth.devices.push_back(std::move(device));
    for (const v1::ImuBatch& batch : result.batches) small.emplace_back().mutable_imu()->CopyFrom(batch);
  }
  lap("IMU: signals, clocks, packet loss");
  {
    const double stop_s = std::min(options.buzzer_stop_s, 0.6 * options.duration_s);
    BuzzerOptions buzzer = options.buzzer;
    buzzer.duration_s = std::min(buzzer.duration_s, 0.5 * stop_s);
    buzzer.stop_device_us = devices.back().clock.to_device_us(stop_s);
    // Later stops while the microphone still hears each one with silence after it.
    for (double t = stop_s + options.buzzer_repeat_s; options.buzzer_repeat_s > 0 && t < options.duration_s - 0.5;
         t += options.buzzer_repeat_s) {
      buzzer.later_stops_device_us.push_back(devices.back().clock.to_device_us(t));
    }
    AudioOptions audio = options.audio;
    audio.t_begin_s = 0.0;
    audio.duration_s = options.duration_s;
    const BuzzerResult result = buzzer_stop(devices.back(), buzzer, audio, options.seed);
    truth.buzzer_stop_camera_s = result.stop_camera_s;
    truth.buzzer_heard_camera_s = result.stop_heard_camera_s;
    small.emplace_back().mutable_sync_event()->CopyFrom(result.stop_event);
    for (const v1::SyncEvent& stop : result.later_stop_events)
      small.emplace_back().mutable_sync_event()->CopyFrom(stop);
    truth.buzzer_later_stops_camera_s = result.later_stops_camera_s;
    for (const auto& chunk : result.audio) small.emplace_back().mutable_audio()->CopyFrom(chunk);
    BleBroadcastOptions ble_options = options.ble;
    ble_options.repeat_until_s = options.duration_s;  // repeated bursts, if any, through the session
    const BleBroadcastResult ble = ble_broadcast_receipts(devices, ble_options, options.seed);
    truth.ble_broadcast_camera_s = ble.broadcast_t_camera_s;
    for (const auto& event : ble.events) small.emplace_back().mutable_sync_event()->CopyFrom(event);
  }

  lap("audio, buzzer, BLE");
  // Header.
  v1::SessionChunk header_chunk;
  v1::SessionHeader& header = *header_chunk.mutable_header();
  header.set_format_version(session::kFormatVersion);
  header.set_subject_id("sim-" + std::to_string(options.seed));
  header.set_sex(options.sex == body::Sex::kMale ? v1::SessionHeader::MALE : v1::SessionHeader::FEMALE);
  if (options.record_height) {
    SimRng height_rng(options.seed, "height_measurement");
    header.set_height_m(body::standing_height(*fitted, options.betas).height_m +
                        options.height_error_m * height_rng.normal());
  }
  for (const SimDeviceTruth& device : truth.devices) {
    auto* d = header.add_imu_devices();
    d->set_device_id(device.device_id);
    v1::ImuDevice::Role role = device.role;
    if (options.arm_imu_roles_swapped && role != v1::ImuDevice::BASE) {
      role = role == v1::ImuDevice::ARM_LEFT ? v1::ImuDevice::ARM_RIGHT : v1::ImuDevice::ARM_LEFT;
    }
    d->set_role(role);
    d->set_nominal_rate_hz(options.imu.rate_hz);
  }
  set_camera_intrinsics(options.depth_intrinsics, header.mutable_depth_intrinsics());
  header.set_depth_rate_hz(options.depth_rate_hz);
  if (options.color) {
    set_camera_intrinsics(options.color_camera.intrinsics, header.mutable_color_intrinsics());
    const Quat q(options.color_camera.color_from_depth.linear());
    auto* transform = header.mutable_color_from_depth();
    transform->mutable_rotation()->set_w(q.w());
    transform->mutable_rotation()->set_x(q.x());
    transform->mutable_rotation()->set_y(q.y());
    transform->mutable_rotation()->set_z(q.z());
    const Vec3 t = options.color_camera.color_from_depth.translation();
    transform->mutable_translation_m()->set_x(t.x());
    transform->mutable_translation_m()->set_y(t.y());
    transform->mutable_translation_m()->set_z(t.z());
    header.set_color_rate_hz(options.depth_rate_hz);
  }
  header.set_audio_sample_rate_hz(options.audio.sample_rate_hz);
  header.set_audio_channels(1);
  (*header.mutable_options())["sim.seed"] = std::to_string(options.seed);
  (*header.mutable_options())["sim.motion"] = options.motion;
  // The forearm stage's W -> K alignment (docs/forearm.md): the base IMU's true mounting.
  (*header.mutable_options())[session::kForearmKFromBKey] =
      session::format_double(truth.K_from_B.w()) + " " + session::format_double(truth.K_from_B.x()) + " " +
      session::format_double(truth.K_from_B.y()) + " " + session::format_double(truth.K_from_B.z());
  // Each IMU's magnetometer calibration from before the session (paper 1, II-E-1), which the
  // IMU stage applies (eq. 3); without it hard iron turns the headings, and through eq. 7 K_from_W.
  for (const SimDeviceTruth& device : truth.devices) {
    const imu::MagCalibration calibration = simulate_mag_precalibration(
        device.errors, options.imu.synth.earth_field, options.imu.synth.error_model.mag_noise_uT, options.seed,
        "mag_precalibration/" + device.device_id);
    (*header.mutable_options())[session::mag_calibration_option_key(device.device_id)] =
        session::format_mag_calibration(calibration);
  }
  sink.write(header_chunk);
  ++truth.chunks;

  // Order the small chunks once; frames are merged in as they are rendered.
  std::vector<std::pair<session::ChunkOrderKey, std::size_t>> order;
  for (std::size_t i = 0; i < small.size(); ++i) order.emplace_back(session::chunk_order_key(small[i], header), i);
  std::stable_sort(order.begin(), order.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  std::size_t next_small = 0;
  v1::EndOfSession counts;
  const auto emit = [&](const v1::SessionChunk& chunk) {
    sink.write(chunk);
    ++truth.chunks;
    switch (chunk.chunk_case()) {
      case v1::SessionChunk::kDepth: counts.set_depth_frames(counts.depth_frames() + 1); break;
      case v1::SessionChunk::kBodyIndex: counts.set_body_index_frames(counts.body_index_frames() + 1); break;
      case v1::SessionChunk::kSkeleton: counts.set_skeleton_frames(counts.skeleton_frames() + 1); break;
      case v1::SessionChunk::kColor: counts.set_color_frames(counts.color_frames() + 1); break;
      case v1::SessionChunk::kImu:
        (*counts.mutable_imu_samples())[chunk.imu().device_id()] += static_cast<std::uint64_t>(chunk.imu().t_us_size());
        break;
      case v1::SessionChunk::kAudio:
        counts.set_audio_chunks(counts.audio_chunks() + 1);
        counts.set_audio_frames(counts.audio_frames() + chunk.audio().pcm_s16le().size() / 2);
        break;
      case v1::SessionChunk::kSyncEvent: counts.set_sync_events(counts.sync_events() + 1); break;
      default: break;
    }
  };
  const auto emit_small_before = [&](const session::ChunkOrderKey* key) {
    while (next_small < order.size() && (key == nullptr || order[next_small].first < *key)) {
      emit(small[order[next_small].second]);
      ++next_small;
    }
  };

  // Frames on `threads` workers; each frame's numbers depend only on its index.
  const raycast::DepthCamera camera(options.depth_intrinsics);
  const CameraSkeletonSimulator skeleton(camera, options.skeleton, options.seed, *render.model);
  const Vec3 floor_normal_K = K_from_Body.linear() * Vec3::UnitY();
  const std::vector<RoomPlane> room = {RoomPlane{floor_normal_K, floor_normal_K.dot(K_from_Body.translation())},
                                       RoomPlane{camera_tilt(options) * Vec3::UnitZ(), options.wall_distance_m}};
  // The room's depth and incidence once; frames redo the error model's incidence near the body.
  const StaticBackground background(camera, room, options.depth_noise);
  const auto frames = static_cast<std::int64_t>(std::floor(options.duration_s * options.depth_rate_hz + 1e-9)) + 1;
  std::vector<double> frame_times_s;
  for (std::int64_t i = 0; i < frames; ++i) frame_times_s.push_back(static_cast<double>(i) / options.depth_rate_hz);
  const std::vector<Eigen::Matrix3Xd> wobble =
      segment_wobble([&](double t) { return pose_skeleton(truth.rest_joints, layout, motion.poses(t)).joints; },
                     frame_times_s, options.soft_tissue);
  lap("soft-tissue wobble (segment springs)");
  std::vector<std::unique_ptr<FrameWorker>> workers;
  for (int w = 0; w < options.threads; ++w) {
    workers.push_back(std::make_unique<FrameWorker>(options, render, layout, camera, skeleton, straps, forearm_straps,
                                                    rest_R_from_F, K_from_Body, room, background, wobble));
  }
  // Workers render frames while this thread writes the earlier ones (the sink may encode files).
  const auto render_frame = [&](int worker, std::int64_t index) {
    FramePlan plan;
    plan.index = index;
    plan.t_s = static_cast<double>(plan.index) / options.depth_rate_hz;
    plan.t_us = std::llround(plan.t_s * 1e6);
    return workers[static_cast<std::size_t>(worker)]->process(plan, motion);
  };
  const auto write_frame = [&](std::int64_t index, FrameOutput& output) {
    lap("waiting for frames");
    const session::ChunkOrderKey key = session::chunk_order_key(output.chunks.front(), header);
    emit_small_before(&key);
    for (const auto& chunk : output.chunks) emit(chunk);
    SimFrameTruth& frame = output.truth;
    const double t_s = static_cast<double>(frame.t_us) * 1e-6;
    for (const SensorKinematics& kin : kinematics) {
      const SensorMotion m = kin.at(std::clamp(t_s, kin.t_begin_s(), kin.t_end_s()));
      frame.imu_p_K.push_back(W_to_K(m.p_W_m));
      frame.K_from_imu.push_back((truth.K_from_W * m.W_from_A).normalized());
    }
    truth.frames.push_back(std::move(frame));
    lap("writing chunks, merging, IMU truth per frame");
    if (progress) progress(SimProgress{index + 1, frames});
    lap("progress callback");
  };
  lap("setup: header, room, frame workers");
  run_ordered<FrameOutput>(options.threads, frames, kFramesAheadPerWorker, render_frame, write_frame);
  emit_small_before(nullptr);
  v1::SessionChunk end;
  *end.mutable_end() = counts;
  sink.write(end);
  ++truth.chunks;
  lap("writing chunks, merging, IMU truth per frame");
  // Blocked waiting costs no CPU; the lap only separates it from the writing.
  truth.cpu_s.erase("waiting for frames");
  for (const auto& worker : workers) {
    for (const auto& [part, seconds] : worker->times()) truth.cpu_s[part] += seconds;
  }
  return truth;
}

}  // namespace posefuse::sim
