// The whole session pipeline (session/pipeline.hpp, make_default_stages) on sessions that a
// structure-aware generator builds from the input bytes, the body fit on or off: a header whose
// options take edge values from the stages' own option tables, then up to kMaxChunks chunks of
// every kind (a blocky person in depth and body index with the camera skeleton over it, colour,
// IMU batches of the header's devices and unknown ones, audio, sync events, the end marker) whose
// timestamps step on, repeat, go back or jump, some with corrupt payloads or NaN values. Random
// bytes would rarely pass the header's validation; built this way nearly every input reaches the
// stages, which is where the fit, the forearm stage and the measures hold state across frames.
//
// Invariants: no crash, no sanitizer report, no allocation beyond -malloc_limit_mb, no hang
// (-timeout); errors only as posefuse::Error; the pipeline's memory budget holds (it ends the
// session with kResourceExhausted rather than growing); every accepted session ends with a Summary.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <fuzzer/FuzzedDataProvider.h>
#include <opencv2/imgproc.hpp>

#include "common/error.hpp"
#include "seeds.hpp"
#include "session/image_codec.hpp"
#include "session/imu_batch.hpp"
#include "session/pipeline.hpp"
#include "session/session_validator.hpp"
#include "session/stages/default_stages.hpp"

using namespace posefuse;

namespace {

constexpr int kMaxChunks = 160;
constexpr std::uint64_t kMaxHeldBytes = 48ull << 20;
constexpr std::int64_t kFrameUs = 33'333;

// A person standing 2 m in front of the camera, Kinect v2 joint order (session.proto
// SkeletonFrame), camera frame: x to the left, y up, z forward.
constexpr double kStandingJoints[session::kSkeletonJointCount][3] = {
    {0, -0.30, 2.0},      {0, 0.0, 2.0},        {0, 0.35, 2.0},      {0, 0.50, 2.0},       {0.18, 0.30, 2.0},
    {0.22, 0.03, 2.0},    {0.24, -0.20, 1.95},  {0.25, -0.28, 1.95}, {-0.18, 0.30, 2.0},   {-0.22, 0.03, 2.0},
    {-0.24, -0.20, 1.95}, {-0.25, -0.28, 1.95}, {0.10, -0.35, 2.0},  {0.10, -0.80, 2.0},   {0.10, -1.20, 2.0},
    {0.10, -1.25, 1.9},   {-0.10, -0.35, 2.0},  {-0.10, -0.80, 2.0}, {-0.10, -1.20, 2.0},  {-0.10, -1.25, 1.9},
    {0, 0.30, 2.0},       {0.26, -0.35, 1.95},  {0.23, -0.30, 1.92}, {-0.26, -0.35, 1.95}, {-0.23, -0.30, 1.92}};
// Bones drawn into the depth image: (joint, joint, radius m).
constexpr struct {
  int a, b;
  double radius_m;
} kBones[] = {{0, 20, 0.15}, {20, 3, 0.07},  {4, 5, 0.05},   {5, 6, 0.04},   {6, 7, 0.04},   {8, 9, 0.05},
              {9, 10, 0.04}, {10, 11, 0.04}, {12, 13, 0.07}, {13, 14, 0.05}, {16, 17, 0.07}, {17, 18, 0.05}};

struct Camera {
  int width, height;
  double f, cx, cy;
};

class CountingSink : public session::ResultSink {
 public:
  void emit(v1::FitResult&& result) override {
    if (result.has_summary()) ++summaries;
  }
  int summaries = 0;
};

// Edge values for one option of the stages' tables: its default, bounds and words, just past the
// bounds, and things that are not numbers.
std::string option_value(FuzzedDataProvider& in, const session::OptionSpec& spec) {
  std::vector<std::string> values = {spec.default_value, "nan", "-1", "0", "1", "1e308", "", "x", "1 0 0 0"};
  for (const auto& bound : {spec.min, spec.max}) {
    if (!bound) continue;
    values.push_back(std::to_string(bound->value));
    values.push_back(std::to_string(bound->value * 1.001 + 1e-9));
    values.push_back(std::to_string(bound->value * 0.999 - 1e-9));
  }
  values.insert(values.end(), spec.words.begin(), spec.words.end());
  return values[in.ConsumeIntegralInRange<std::size_t>(0, values.size() - 1)];
}

v1::SessionHeader make_header(FuzzedDataProvider& in, const Camera& camera, bool fit_enabled,
                              const std::vector<const session::OptionSpec*>& options) {
  v1::SessionHeader h = fuzz::tiny_header();
  h.clear_imu_devices();
  const std::pair<const char*, v1::ImuDevice::Role> devices[] = {
      {"wrist_l", v1::ImuDevice::ARM_LEFT}, {"wrist_r", v1::ImuDevice::ARM_RIGHT}, {"base", v1::ImuDevice::BASE}};
  for (const auto& [id, role] : devices) {
    if (in.ConsumeIntegralInRange<int>(0, 3) == 0) continue;
    v1::ImuDevice* d = h.add_imu_devices();
    d->set_device_id(id);
    d->set_role(role);
    d->set_nominal_rate_hz(in.ConsumeBool() ? 100 : 80);
  }
  for (auto* k : {h.mutable_depth_intrinsics(), h.mutable_color_intrinsics()}) {
    k->set_width(static_cast<std::uint32_t>(camera.width));
    k->set_height(static_cast<std::uint32_t>(camera.height));
    k->set_fx(camera.f);
    k->set_fy(camera.f);
    k->set_cx(camera.cx);
    k->set_cy(camera.cy);
  }
  h.mutable_color_from_depth()->mutable_translation_m()->set_x(in.ConsumeBool() ? 0.0 : -0.05);
  (*h.mutable_options())["fit.enabled"] = fit_enabled ? "true" : "false";
  const int option_count = in.ConsumeIntegralInRange<int>(0, 4);
  for (int i = 0; i < option_count && !options.empty(); ++i) {
    const session::OptionSpec& spec = *options[in.ConsumeIntegralInRange<std::size_t>(0, options.size() - 1)];
    (*h.mutable_options())[spec.key] = option_value(in, spec);
  }
  return h;
}

// The next timestamp of a stream: usually one period on; sometimes the same, earlier, or far off.
// Steps saturate at the int64 ends, which the generator reaches on purpose.
std::int64_t next_time(FuzzedDataProvider& in, std::int64_t& t_us, std::int64_t period_us) {
  constexpr std::int64_t kMax = std::numeric_limits<std::int64_t>::max();
  constexpr std::int64_t kMin = std::numeric_limits<std::int64_t>::min();
  auto step = [&](std::int64_t by) {
    if (__builtin_add_overflow(t_us, by, &t_us)) t_us = by > 0 ? kMax : kMin;
  };
  switch (in.ConsumeIntegralInRange<int>(0, 15)) {
    case 0: break;
    case 1: step(-period_us); break;
    case 2: step(100 * period_us); break;
    case 3: t_us = in.ConsumeBool() ? kMax : kMin; break;
    default: step(period_us);
  }
  return t_us;
}

// The standing person with each joint moved by up to +-10 cm, some joints NaN or untracked.
std::vector<cv::Point3d> person(FuzzedDataProvider& in) {
  std::vector<cv::Point3d> joints;
  const double sway = 0.1 * (in.ConsumeIntegralInRange<int>(0, 20) - 10) / 10.0;
  for (const auto& p : kStandingJoints) {
    const double wiggle =
        in.ConsumeIntegralInRange<int>(0, 8) == 0 ? 0.1 * (in.ConsumeIntegralInRange<int>(0, 20) - 10) / 10.0 : 0.0;
    joints.emplace_back(p[0] + sway + wiggle, p[1], p[2] + wiggle);
  }
  if (in.ConsumeIntegralInRange<int>(0, 31) == 0) joints[in.ConsumeIntegralInRange<int>(0, 24)].x = std::nan("");
  return joints;
}

// Depth (mm) and body index of `joints` drawn as thick bones; the rest background or no reading.
void draw_person(const Camera& camera, const std::vector<cv::Point3d>& joints, std::uint8_t body_id,
                 std::uint16_t background_mm, cv::Mat& depth_mm, cv::Mat& body_index) {
  depth_mm.create(camera.height, camera.width, CV_16UC1);
  depth_mm.setTo(background_mm);
  body_index.create(camera.height, camera.width, CV_8UC1);
  body_index.setTo(255);
  auto pixel = [&](const cv::Point3d& p) {
    return cv::Point(static_cast<int>(std::lround(camera.cx - camera.f * p.x / p.z)),
                     static_cast<int>(std::lround(camera.cy - camera.f * p.y / p.z)));
  };
  for (const auto& bone : kBones) {
    const cv::Point3d& a = joints[static_cast<std::size_t>(bone.a)];
    const cv::Point3d& b = joints[static_cast<std::size_t>(bone.b)];
    if (!std::isfinite(a.x + a.y + a.z + b.x + b.y + b.z) || a.z < 0.5 || b.z < 0.5) continue;
    const int thickness = std::max(1, static_cast<int>(2.0 * bone.radius_m * camera.f / a.z));
    const auto mm = static_cast<double>(std::lround(1000.0 * (a.z + b.z) / 2.0 - 1000.0 * bone.radius_m));
    cv::line(depth_mm, pixel(a), pixel(b), cv::Scalar(mm), thickness);
    cv::line(body_index, pixel(a), pixel(b), cv::Scalar(body_id), thickness);
  }
}

v1::SkeletonFrame skeleton(FuzzedDataProvider& in, const std::vector<cv::Point3d>& joints, std::int64_t t_us,
                           std::uint32_t body_id) {
  v1::SkeletonFrame s;
  s.set_t_us(t_us);
  s.set_body_id(body_id);
  const int joint_count =
      in.ConsumeIntegralInRange<int>(0, 63) == 0 ? in.ConsumeIntegralInRange<int>(0, 26) : session::kSkeletonJointCount;
  for (int j = 0; j < joint_count; ++j) {
    const cv::Point3d& p = joints[static_cast<std::size_t>(j % session::kSkeletonJointCount)];
    v1::SkeletonJoint* joint = s.add_joints();
    joint->mutable_position_m()->set_x(p.x);
    joint->mutable_position_m()->set_y(p.y);
    joint->mutable_position_m()->set_z(p.z);
    joint->set_state(in.ConsumeIntegralInRange<int>(0, 15) == 0 ? v1::SkeletonJoint::INFERRED
                                                                : v1::SkeletonJoint::TRACKED);
    joint->mutable_orientation()->set_w(1);
  }
  return s;
}

v1::ImuBatch imu_batch(FuzzedDataProvider& in, const std::string& device, std::int64_t& t_us) {
  std::vector<imu::ImuSample> samples(static_cast<std::size_t>(in.ConsumeIntegralInRange<int>(1, 32)));
  const double turn = 0.5 * (in.ConsumeIntegralInRange<int>(0, 20) - 10);
  for (imu::ImuSample& s : samples) {
    s.t_us = next_time(in, t_us, 10'000);
    s.gyr_rad_s = {0.1 * turn, -0.05, 0.02};
    s.acc_m_s2 = {0.3 * turn, 0.1, 9.81};
    s.mag_uT = {21.5, -3.25, -40.0};
    if (in.ConsumeIntegralInRange<int>(0, 63) == 0) s.acc_m_s2.x() = std::nan("");
  }
  return session::batch_from_samples(device, samples);
}

// Flips, cuts or lengthens a payload now and then: a corrupt frame among good ones.
void damage(FuzzedDataProvider& in, std::string& bytes) {
  switch (in.ConsumeIntegralInRange<int>(0, 31)) {
    case 0:
      if (!bytes.empty()) bytes[in.ConsumeIntegralInRange<std::size_t>(0, bytes.size() - 1)] ^= 0x5A;
      break;
    case 1: bytes.resize(bytes.size() / 2); break;
    case 2: bytes.append(17, '\x7f'); break;
    default: break;
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::init_harness([] {
    // Byte strings for the generator: all zero (every choice its first), all 0xFF, and a ramp.
    fuzz::Seeds seeds;
    seeds.push_back({"zeros", std::string(4096, '\0')});
    seeds.push_back({"ones", std::string(4096, '\xff')});
    std::string ramp(4096, '\0');
    for (std::size_t i = 0; i < ramp.size(); ++i) ramp[i] = static_cast<char>(i * 7 + i / 13);
    seeds.push_back({"ramp", ramp});
    return seeds;
  });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider in(data, size);
  const bool fit_enabled = in.ConsumeBool();
  const int scale = in.ConsumeIntegralInRange<int>(1, 8);
  const Camera camera{8 * scale, 6 * scale, 0.7 * 8 * scale, 4.0 * scale - 0.5, 3.0 * scale - 0.5};

  auto stages = session::make_default_stages();
  std::vector<const session::OptionSpec*> options;
  for (const auto& stage : stages) {
    for (const session::OptionSpec& spec : stage->options()) options.push_back(&spec);
  }
  const v1::SessionHeader header = make_header(in, camera, fit_enabled, options);
  const std::vector<std::string> color_images = {fuzz::encoded_image(camera.width, camera.height, CV_8UC3, ".jpg"),
                                                 fuzz::encoded_image(camera.width, camera.height, CV_8UC3, ".png")};

  CountingSink sink;
  session::PipelineOptions pipeline_options;
  pipeline_options.max_held_bytes = kMaxHeldBytes;
  pipeline_options.max_item_errors = 40;
  session::SessionPipeline pipeline(std::move(stages), sink, pipeline_options);
  session::SessionValidator shadow;  // the counts a correct end marker carries
  std::int64_t camera_t_us = 1'000'000, imu_t_us = 990'000, other_t_us = 1'000'000;
  bool ended_by_error = false;
  try {
    v1::SessionChunk chunk;
    *chunk.mutable_header() = header;
    pipeline.push(chunk);
    try {
      shadow.check(chunk);
    } catch (const Error&) {
    }
    const std::uint32_t body_id = in.ConsumeBool() ? 0 : 1;
    std::vector<cv::Point3d> joints = person(in);
    for (int i = 0; i < kMaxChunks && in.remaining_bytes() > 0 && !pipeline.ended(); ++i) {
      chunk.Clear();
      switch (in.ConsumeIntegralInRange<int>(0, 9)) {
        case 0:
        case 1: {  // a camera frame: depth, body index and skeleton at one time
          joints = person(in);
          const std::int64_t t_us = next_time(in, camera_t_us, kFrameUs);
          cv::Mat depth, ids;
          draw_person(camera, joints, static_cast<std::uint8_t>(body_id), in.ConsumeBool() ? 0 : 3500, depth, ids);
          const v1::DepthFrame::Encoding depth_encodings[] = {v1::DepthFrame::RAW_U16_LE, v1::DepthFrame::PNG16,
                                                              v1::DepthFrame::ZSTD_U16_LE};
          *chunk.mutable_depth() = session::encode_depth(depth, in.PickValueInArray(depth_encodings), t_us);
          damage(in, *chunk.mutable_depth()->mutable_data());
          pipeline.push(chunk);
          chunk.Clear();
          const v1::BodyIndexFrame::Encoding index_encodings[] = {v1::BodyIndexFrame::RAW_U8, v1::BodyIndexFrame::PNG8,
                                                                  v1::BodyIndexFrame::ZSTD_U8};
          *chunk.mutable_body_index() = session::encode_body_index(ids, in.PickValueInArray(index_encodings), t_us);
          damage(in, *chunk.mutable_body_index()->mutable_data());
          pipeline.push(chunk);
          chunk.Clear();
          *chunk.mutable_skeleton() = skeleton(in, joints, t_us, body_id);
          break;
        }
        case 2: {
          v1::ColorFrame* color = chunk.mutable_color();
          color->set_t_us(next_time(in, other_t_us, kFrameUs));
          color->set_width(static_cast<std::uint32_t>(camera.width));
          color->set_height(static_cast<std::uint32_t>(camera.height));
          const bool jpeg = in.ConsumeBool();
          color->set_encoding(jpeg ? v1::ColorFrame::JPEG : v1::ColorFrame::PNG);
          color->set_data(color_images[jpeg ? 0 : 1]);
          damage(in, *color->mutable_data());
          break;
        }
        case 3:
        case 4:
        case 5:
        case 6: {
          const char* ids[] = {"wrist_l", "wrist_r", "base", "wrist_x"};
          *chunk.mutable_imu() = imu_batch(in, in.PickValueInArray(ids), imu_t_us);
          break;
        }
        case 7: {
          v1::AudioChunk* audio = chunk.mutable_audio();
          audio->set_t_us(next_time(in, other_t_us, 20'000));
          audio->set_sample_rate_hz(16'000);
          audio->set_channels(1);
          audio->set_pcm_s16le(std::string(2 * in.ConsumeIntegralInRange<int>(0, 320), '\x21'));
          break;
        }
        case 8: {
          v1::SyncEvent* sync = chunk.mutable_sync_event();
          sync->set_t_us(next_time(in, other_t_us, 10'000));
          const char* ids[] = {"camera", "wrist_l", "wrist_r", "base"};
          sync->set_device_id(in.PickValueInArray(ids));
          const v1::SyncEvent::Kind kinds[] = {v1::SyncEvent::BUZZER_STOP, v1::SyncEvent::BLE_BROADCAST_RECEIPT};
          sync->set_kind(in.PickValueInArray(kinds));
          break;
        }
        default:  // the end marker, with the right counts or not
          *chunk.mutable_end() = shadow.counts();
          if (in.ConsumeIntegralInRange<int>(0, 3) == 0) chunk.mutable_end()->set_depth_frames(7);
          break;
      }
      try {
        shadow.check(chunk);
      } catch (const Error&) {
      }
      pipeline.push(chunk);
    }
    if (!pipeline.ended()) {
      chunk.Clear();
      *chunk.mutable_end() = shadow.counts();
      pipeline.push(chunk);
    }
    pipeline.close();
  } catch (const Error&) {
    ended_by_error = true;
  }
  if (!ended_by_error && sink.summaries != 1) fuzz::invariant_failed("a session that ended well sent no summary");
  if (pipeline.held_bytes() > kMaxHeldBytes + (8u << 20)) {
    fuzz::invariant_failed("the pipeline holds more than its memory budget");
  }
  return 0;
}
