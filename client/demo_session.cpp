#include "client/demo_session.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>

#include <opencv2/core.hpp>

#include "common/error.hpp"
#include "imu/imu_sample.hpp"
#include "session/chunk_file.hpp"
#include "session/chunk_order.hpp"
#include "session/directory_writer.hpp"
#include "session/image_codec.hpp"
#include "session/imu_batch.hpp"
#include "session/session_validator.hpp"

namespace posefuse::demo {

namespace {

using geometry::Quat;
using geometry::Vec3;

using std::numbers::pi;
constexpr double kGravity_m_s2 = 9.81;
constexpr double kRestS = 1.5;  // the arm rests this long first, so the filter can settle

Quat axis_rotation(const Vec3& axis, double angle_rad) { return Quat(Eigen::AngleAxisd(angle_rad, axis)); }

// Earth-like field in W (x north, z up): 49 uT, pointing 60 degrees below the horizon.
Vec3 earth_field_W_uT() {
  const double dip_rad = 60.0 * pi / 180.0;
  return {49.0 * std::cos(dip_rad), 0.0, -49.0 * std::sin(dip_rad)};
}

// 0 before kRestS, 1 one second later, smooth in between (the motion starts gently).
double motion_ramp(double t_s) {
  const double x = std::clamp(t_s - kRestS, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

// Body angular rate in A from the truth by central differences:
// q(t + h) = q(t - h) * exp(omega_A * 2h).
Vec3 arm_angular_rate_A(double t_s) {
  constexpr double h = 1e-4;
  const Quat before = demo_arm_W_from_A(t_s - h);
  const Quat after = demo_arm_W_from_A(t_s + h);
  return geometry::rotation_vector_from_quat(before.conjugate() * after) / (2.0 * h);
}

struct Noise {
  std::mt19937 rng;
  Vec3 gaussian(double sigma) {
    std::normal_distribution<double> n(0.0, sigma);
    return {n(rng), n(rng), n(rng)};
  }
};

imu::ImuSample imu_sample(std::int64_t t_us, const Quat& W_from_S, const Vec3& rate_S, const Vec3& gyro_bias,
                          Noise& noise) {
  const Quat S_from_W = W_from_S.conjugate();
  imu::ImuSample s;
  s.t_us = t_us;
  s.gyr_rad_s = rate_S + gyro_bias + noise.gaussian(0.005);
  s.acc_m_s2 = S_from_W * Vec3(0.0, 0.0, kGravity_m_s2) + noise.gaussian(0.05);
  s.mag_uT = S_from_W * earth_field_W_uT() + noise.gaussian(0.4);
  return s;
}

void add_imu_stream(const std::string& device_id, std::int64_t clock_start_us, bool moving,
                    const DemoSessionOptions& options, Noise& noise, std::vector<v1::SessionChunk>& chunks) {
  const Vec3 gyro_bias = moving ? Vec3(0.010, -0.007, 0.004) : Vec3(-0.004, 0.006, 0.002);
  const int n = static_cast<int>(std::floor(options.duration_s * options.imu_rate_hz));
  const double period_us = 1e6 / options.imu_rate_hz;
  std::vector<imu::ImuSample> batch;
  for (int k = 0; k < n; ++k) {
    const double t_s = k / options.imu_rate_hz;
    const auto t_us = clock_start_us + static_cast<std::int64_t>(std::llround(k * period_us));
    const Quat W_from_S = moving ? demo_arm_W_from_A(t_s) : demo_base_W_from_B();
    const Vec3 rate_S = moving ? arm_angular_rate_A(t_s) : Vec3::Zero();
    batch.push_back(imu_sample(t_us, W_from_S, rate_S, gyro_bias, noise));
    if (static_cast<int>(batch.size()) == options.imu_samples_per_batch || k == n - 1) {
      *chunks.emplace_back().mutable_imu() = session::batch_from_samples(device_id, batch);
      batch.clear();
    }
  }
}

// A stick figure facing the camera 2 m away, swaying sideways by `sway_m` (frame K, metres).
constexpr std::array<std::array<double, 3>, 25> kSkeleton_K_m = {{
    {0.00, -0.10, 2.00},  {0.00, 0.15, 2.00},   {0.00, 0.45, 2.00},   {0.00, 0.60, 2.00},   {0.18, 0.38, 2.00},
    {0.25, 0.12, 2.00},   {0.28, -0.10, 1.95},  {0.29, -0.18, 1.95},  {-0.18, 0.38, 2.00},  {-0.25, 0.12, 2.00},
    {-0.28, -0.10, 1.95}, {-0.29, -0.18, 1.95}, {0.10, -0.12, 2.00},  {0.10, -0.55, 2.00},  {0.10, -0.95, 2.00},
    {0.10, -1.00, 1.90},  {-0.10, -0.12, 2.00}, {-0.10, -0.55, 2.00}, {-0.10, -0.95, 2.00}, {-0.10, -1.00, 1.90},
    {0.00, 0.38, 2.00},   {0.30, -0.26, 1.95},  {0.26, -0.20, 1.93},  {-0.30, -0.26, 1.95}, {-0.26, -0.20, 1.93},
}};

v1::SkeletonFrame skeleton_frame(std::int64_t t_us, double sway_m) {
  v1::SkeletonFrame frame;
  frame.set_t_us(t_us);
  frame.set_body_id(0);
  for (const auto& p : kSkeleton_K_m) {
    v1::SkeletonJoint& joint = *frame.add_joints();
    joint.mutable_position_m()->set_x(p[0] + sway_m);
    joint.mutable_position_m()->set_y(p[1]);
    joint.mutable_position_m()->set_z(p[2]);
    joint.set_state(v1::SkeletonJoint::TRACKED);
  }
  return frame;
}

v1::CameraIntrinsics depth_intrinsics(const DemoSessionOptions& options) {
  // Kinect v2 depth camera (512x424, f ~ 365 px) scaled to the demo's image size.
  const double scale = options.depth_width / 512.0;
  v1::CameraIntrinsics k;
  k.set_width(options.depth_width);
  k.set_height(options.depth_height);
  k.set_fx(365.5 * scale);
  k.set_fy(365.5 * scale);
  k.set_cx(0.5 * (options.depth_width - 1));
  k.set_cy(0.5 * (options.depth_height - 1));
  return k;
}

// Depth (mm) and body index of a wall at 3 m and an upright ellipse "person" at 2 m.
void camera_images(const v1::CameraIntrinsics& k, double sway_m, cv::Mat& depth_mm, cv::Mat& body_index) {
  const int w = static_cast<int>(k.width()), h = static_cast<int>(k.height());
  depth_mm = cv::Mat(h, w, CV_16UC1, cv::Scalar(3000));
  body_index = cv::Mat(h, w, CV_8UC1, cv::Scalar(255));
  const double z_m = 2.0;
  // u = cx - fx * x / z (K's x points left, the image's u right).
  const double centre_u = k.cx() - k.fx() * sway_m / z_m;
  const double centre_v = k.cy();
  const double radius_u = k.fx() * 0.25 / z_m, radius_v = k.fy() * 0.8 / z_m;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const double du = (u - centre_u) / radius_u, dv = (v - centre_v) / radius_v;
      if (du * du + dv * dv <= 1.0) {
        depth_mm.at<std::uint16_t>(v, u) = static_cast<std::uint16_t>(z_m * 1000.0);
        body_index.at<std::uint8_t>(v, u) = 0;
      }
    }
  }
}

void add_camera_streams(const DemoSessionOptions& options, const v1::CameraIntrinsics& k,
                        std::vector<v1::SessionChunk>& chunks) {
  const int n = static_cast<int>(std::floor(options.duration_s * options.camera_rate_hz));
  for (int i = 0; i < n; ++i) {
    const double t_s = i / options.camera_rate_hz;
    const auto t_us = kCameraClockStartUs + static_cast<std::int64_t>(std::llround(t_s * 1e6));
    const double sway_m = 0.05 * std::sin(2.0 * pi * 0.2 * t_s);
    cv::Mat depth_mm, body_index;
    camera_images(k, sway_m, depth_mm, body_index);
    *chunks.emplace_back().mutable_depth() = session::encode_depth(depth_mm, v1::DepthFrame::PNG16, t_us);
    *chunks.emplace_back().mutable_body_index() =
        session::encode_body_index(body_index, v1::BodyIndexFrame::PNG8, t_us);
    *chunks.emplace_back().mutable_skeleton() = skeleton_frame(t_us, sway_m);
  }
}

v1::SessionHeader demo_header(const DemoSessionOptions& options) {
  v1::SessionHeader header;
  header.set_format_version(session::kFormatVersion);
  header.set_subject_id("demo-subject");
  auto add_device = [&](const char* id, v1::ImuDevice::Role role) {
    v1::ImuDevice& device = *header.add_imu_devices();
    device.set_device_id(id);
    device.set_role(role);
    device.set_nominal_rate_hz(options.imu_rate_hz);
  };
  add_device(kArmDevice, v1::ImuDevice::ARM_LEFT);
  add_device(kBaseDevice, v1::ImuDevice::BASE);
  *header.mutable_depth_intrinsics() = depth_intrinsics(options);
  header.set_depth_rate_hz(options.camera_rate_hz);
  (*header.mutable_options())["demo.generator"] =
      "posefuse demo-session: a small synthetic stream for tests (realistic sessions: posefuse-sim)";
  return header;
}

}  // namespace

Quat demo_arm_W_from_A(double t_s) {
  const double a = motion_ramp(t_s);
  const double yaw = 0.3 + a * 0.8 * std::sin(2.0 * pi * 0.15 * t_s);
  const double pitch = a * 0.5 * std::sin(2.0 * pi * 0.23 * t_s + 0.4);
  const double roll = a * 0.9 * std::sin(2.0 * pi * 0.31 * t_s + 1.0);
  return axis_rotation(Vec3::UnitZ(), yaw) * axis_rotation(Vec3::UnitY(), pitch) * axis_rotation(Vec3::UnitX(), roll);
}

Quat demo_base_W_from_B() { return axis_rotation(Vec3::UnitZ(), 0.7) * axis_rotation(Vec3::UnitX(), 0.05); }

std::vector<v1::SessionChunk> make_demo_session(const DemoSessionOptions& options) {
  const v1::SessionHeader header = demo_header(options);
  Noise noise{std::mt19937(options.seed)};
  std::vector<v1::SessionChunk> data;
  add_imu_stream(kArmDevice, kArmClockStartUs, true, options, noise, data);
  add_imu_stream(kBaseDevice, kBaseClockStartUs, false, options, noise, data);
  add_camera_streams(options, header.depth_intrinsics(), data);
  std::stable_sort(data.begin(), data.end(), [&](const auto& a, const auto& b) {
    return session::chunk_order_key(a, header) < session::chunk_order_key(b, header);
  });

  std::vector<v1::SessionChunk> chunks;
  chunks.reserve(data.size() + 2);
  *chunks.emplace_back().mutable_header() = header;
  for (auto& chunk : data) chunks.push_back(std::move(chunk));
  // The end marker carries what the validator counted, so it matches by construction; the
  // validator also proves the generator made a valid session (a failure here is our bug).
  session::SessionValidator validator;
  for (const auto& chunk : chunks) validator.check(chunk);
  *chunks.emplace_back().mutable_end() = validator.counts();
  validator.check(chunks.back());
  return chunks;
}

std::uint64_t write_demo_session(const std::filesystem::path& out, const DemoSessionOptions& options) {
  const std::vector<v1::SessionChunk> chunks = make_demo_session(options);
  std::unique_ptr<session::ChunkSink> sink;
  if (out.extension() == ".pfchunks") {
    sink = std::make_unique<session::ChunkFileWriter>(out);
  } else {
    sink = std::make_unique<session::DirectoryWriter>(out);
  }
  for (const auto& chunk : chunks) sink->write(chunk);
  sink->finish();
  return chunks.size();
}

}  // namespace posefuse::demo
