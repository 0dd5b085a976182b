#include "fixture.hpp"

#include <google/protobuf/util/message_differencer.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numbers>
#include <opencv2/imgcodecs.hpp>

#include "session/chunk_file.hpp"
#include "session/chunk_order.hpp"
#include "session/image_codec.hpp"
#include "session/imu_batch.hpp"
#include "session/session_validator.hpp"

namespace posefuse::session::testing {

namespace {

constexpr int kWidth = 16;
constexpr int kHeight = 12;
constexpr std::int64_t kCameraStartUs = 1'000'000;
constexpr std::int64_t kFramePeriodUs = 33'333;
constexpr int kImuSamples = 70;
constexpr std::int64_t kImuPeriodUs = 12'500;  // 80 Hz
constexpr int kImuBatch = 32;                  // matches layout::kImuSamplesPerBatch
constexpr std::uint32_t kAudioRateHz = 16'000;
constexpr int kAudioChunkFrames = 1'600;  // 100 ms

void set_intrinsics(v1::CameraIntrinsics* k, double f) {
  k->set_width(kWidth);
  k->set_height(kHeight);
  k->set_fx(f);
  k->set_fy(f * 1.01);
  k->set_cx(7.5);
  k->set_cy(5.5);
  k->set_k1(0.09);
  k->set_k2(-0.27);
  k->set_k3(0.1);
  k->set_p1(0.001);
  k->set_p2(-0.0005);
}

v1::SessionHeader make_header() {
  v1::SessionHeader h;
  h.set_format_version(kFormatVersion);
  h.set_subject_id("S-0042");
  h.set_sex(v1::SessionHeader::FEMALE);
  h.set_height_m(1.68);
  const std::pair<const char*, v1::ImuDevice::Role> devices[] = {
      {"wrist_l", v1::ImuDevice::ARM_LEFT}, {"wrist_r", v1::ImuDevice::ARM_RIGHT}, {"base", v1::ImuDevice::BASE}};
  for (const auto& [id, role] : devices) {
    v1::ImuDevice* d = h.add_imu_devices();
    d->set_device_id(id);
    d->set_role(role);
    d->set_nominal_rate_hz(80);
  }
  set_intrinsics(h.mutable_depth_intrinsics(), 14.2);
  set_intrinsics(h.mutable_color_intrinsics(), 18.9);
  const double half = 0.01;  // a 0.02 rad turn about y
  h.mutable_color_from_depth()->mutable_rotation()->set_w(std::cos(half));
  h.mutable_color_from_depth()->mutable_rotation()->set_y(std::sin(half));
  h.mutable_color_from_depth()->mutable_translation_m()->set_x(-0.052);
  h.set_depth_rate_hz(30);
  h.set_color_rate_hz(30);
  h.set_audio_sample_rate_hz(kAudioRateHz);
  h.set_audio_channels(1);
  (*h.mutable_options())["fit.max_iterations"] = "20";
  return h;
}

cv::Mat depth_image(int frame) {
  cv::Mat depth(kHeight, kWidth, CV_16UC1);
  for (int r = 0; r < kHeight; ++r) {
    for (int c = 0; c < kWidth; ++c) {
      // A slanted plane with a hole (0 = no reading) and a far pixel near the sensor's range.
      depth.at<std::uint16_t>(r, c) = static_cast<std::uint16_t>(1800 + 7 * c + 3 * r + frame);
    }
  }
  depth.at<std::uint16_t>(2, 3) = 0;
  depth.at<std::uint16_t>(9, 14) = 8000;
  return depth;
}

cv::Mat body_index_image(int frame) {
  cv::Mat ids(kHeight, kWidth, CV_8UC1, cv::Scalar(255));
  ids(cv::Rect(4 + frame, 2, 6, 8)).setTo(0);
  ids(cv::Rect(12, 1, 3, 3)).setTo(2);
  return ids;
}

v1::SkeletonFrame skeleton(int frame, std::uint32_t body_id) {
  v1::SkeletonFrame s;
  s.set_t_us(kCameraStartUs + frame * kFramePeriodUs);
  s.set_body_id(body_id);
  for (int j = 0; j < 25; ++j) {
    v1::SkeletonJoint* joint = s.add_joints();
    joint->mutable_position_m()->set_x(0.01 * j - 0.1 + 0.3 * body_id);
    joint->mutable_position_m()->set_y(0.5 - 0.04 * j + 0.001 * frame);
    joint->mutable_position_m()->set_z(2.0 + 0.1 / (j + 1));
    joint->set_state(j % 7 == 3 ? v1::SkeletonJoint::INFERRED
                     : j >= 21  ? v1::SkeletonJoint::NOT_TRACKED
                                : v1::SkeletonJoint::TRACKED);
    if (j < 21) {  // hand tips and thumbs carry no orientation in the Kinect SDK
      const double angle = 0.1 * j + 0.01 * frame;
      const double axis_norm = std::sqrt(1.0 + 4.0 + 9.0);
      joint->mutable_orientation()->set_w(std::cos(angle / 2));
      joint->mutable_orientation()->set_x(std::sin(angle / 2) * 1.0 / axis_norm);
      joint->mutable_orientation()->set_y(std::sin(angle / 2) * 2.0 / axis_norm);
      joint->mutable_orientation()->set_z(std::sin(angle / 2) * 3.0 / axis_norm);
    }
  }
  return s;
}

std::string encoded(const cv::Mat& image, const char* ext) {
  std::vector<unsigned char> bytes;
  cv::imencode(ext, image, bytes);
  return std::string(bytes.begin(), bytes.end());
}

v1::ColorFrame color(int frame, v1::ColorFrame::Encoding encoding) {
  cv::Mat bgr(kHeight, kWidth, CV_8UC3, cv::Scalar(40, 90 + 10 * frame, 200));
  v1::ColorFrame c;
  c.set_t_us(kCameraStartUs + frame * kFramePeriodUs + 1'000);
  c.set_width(kWidth);
  c.set_height(kHeight);
  c.set_encoding(encoding);
  c.set_data(encoded(bgr, encoding == v1::ColorFrame::JPEG ? ".jpg" : ".png"));
  return c;
}

std::vector<v1::ImuBatch> imu_batches(const std::string& device_id, std::int64_t clock_start_us, double phase) {
  std::vector<imu::ImuSample> samples(kImuSamples);
  for (int i = 0; i < kImuSamples; ++i) {
    imu::ImuSample& s = samples[static_cast<std::size_t>(i)];
    const double t = i * 0.0125;
    s.t_us = clock_start_us + i * kImuPeriodUs;
    s.gyr_rad_s = {0.3 * std::sin(2 * t + phase), -0.1, 0.05 * std::cos(t)};
    s.acc_m_s2 = {0.2 * std::cos(t + phase), 0.1, 9.81};
    s.mag_uT = {21.5 + phase, -3.25, -40.125};
    if (i == 17) s.mag_uT = imu::Vec3::Constant(std::nan(""));  // a missing mag reading
    // Values pass through float on the wire; store them as floats so comparisons are exact.
    for (imu::Vec3* v : {&s.gyr_rad_s, &s.acc_m_s2, &s.mag_uT}) {
      *v = v->cast<float>().cast<double>();
    }
  }
  std::vector<v1::ImuBatch> batches;
  for (int first = 0; first < kImuSamples; first += kImuBatch) {
    const auto begin = samples.begin() + first;
    const auto end = samples.begin() + std::min(first + kImuBatch, kImuSamples);
    batches.push_back(batch_from_samples(device_id, {begin, end}));
  }
  return batches;
}

v1::AudioChunk audio(int chunk) {
  v1::AudioChunk a;
  a.set_t_us(kCameraStartUs + chunk * 100'000);
  a.set_sample_rate_hz(kAudioRateHz);
  a.set_channels(1);
  std::string pcm(2 * kAudioChunkFrames, '\0');
  for (int i = 0; i < kAudioChunkFrames; ++i) {
    const double t = (chunk * kAudioChunkFrames + i) / double(kAudioRateHz);
    const auto value = static_cast<std::int16_t>(12000 * std::sin(2 * std::numbers::pi * 440 * t));
    const auto bits = static_cast<std::uint16_t>(value);
    pcm[2 * i] = static_cast<char>(bits & 0xFF);
    pcm[2 * i + 1] = static_cast<char>(bits >> 8);
  }
  a.set_pcm_s16le(pcm);
  return a;
}

v1::SyncEvent sync_event(std::int64_t t_us, const char* device, v1::SyncEvent::Kind kind, std::string payload) {
  v1::SyncEvent e;
  e.set_t_us(t_us);
  e.set_device_id(device);
  e.set_kind(kind);
  e.set_payload(std::move(payload));
  return e;
}

}  // namespace

std::vector<SessionChunk> make_session() {
  const v1::SessionHeader header = make_header();
  std::vector<SessionChunk> data;
  for (int f = 0; f < 3; ++f) {
    const std::int64_t t_us = kCameraStartUs + f * kFramePeriodUs;
    *data.emplace_back().mutable_depth() = encode_depth(depth_image(f), v1::DepthFrame::PNG16, t_us);
    *data.emplace_back().mutable_body_index() = encode_body_index(body_index_image(f), v1::BodyIndexFrame::PNG8, t_us);
    *data.emplace_back().mutable_skeleton() = skeleton(f, 0);
  }
  *data.emplace_back().mutable_skeleton() = skeleton(1, 2);
  *data.emplace_back().mutable_color() = color(0, v1::ColorFrame::PNG);
  *data.emplace_back().mutable_color() = color(1, v1::ColorFrame::JPEG);
  const std::tuple<const char*, std::int64_t, double> devices[] = {
      {"wrist_l", 950'000, 0.0}, {"wrist_r", 5'000'000, 0.7}, {"base", 1'010'000, 1.3}};
  for (const auto& [id, start, phase] : devices) {
    for (v1::ImuBatch& batch : imu_batches(id, start, phase)) *data.emplace_back().mutable_imu() = batch;
  }
  for (int a = 0; a < 3; ++a) *data.emplace_back().mutable_audio() = audio(a);
  *data.emplace_back().mutable_sync_event() = sync_event(990'000, "wrist_l", v1::SyncEvent::BUZZER_STOP, "");
  *data.emplace_back().mutable_sync_event() =
      sync_event(1'050'000, "camera", v1::SyncEvent::OTHER, std::string("\x00\xff,7", 4));
  *data.emplace_back().mutable_sync_event() =
      sync_event(5'200'000, "wrist_r", v1::SyncEvent::BLE_BROADCAST_RECEIPT, std::string("\x01\x02\x00\x00", 4));

  std::stable_sort(data.begin(), data.end(), [&](const SessionChunk& a, const SessionChunk& b) {
    return chunk_order_key(a, header) < chunk_order_key(b, header);
  });
  std::vector<SessionChunk> chunks;
  *chunks.emplace_back().mutable_header() = header;
  for (SessionChunk& c : data) chunks.push_back(std::move(c));
  chunks.emplace_back().mutable_end();
  recount_end(chunks);
  return chunks;
}

void recount_end(std::vector<SessionChunk>& chunks) {
  v1::EndOfSession end;
  for (const SessionChunk& c : chunks) {
    switch (c.chunk_case()) {
      case SessionChunk::kDepth: end.set_depth_frames(end.depth_frames() + 1); break;
      case SessionChunk::kBodyIndex: end.set_body_index_frames(end.body_index_frames() + 1); break;
      case SessionChunk::kSkeleton: end.set_skeleton_frames(end.skeleton_frames() + 1); break;
      case SessionChunk::kColor: end.set_color_frames(end.color_frames() + 1); break;
      case SessionChunk::kImu: (*end.mutable_imu_samples())[c.imu().device_id()] += c.imu().t_us_size(); break;
      case SessionChunk::kAudio:
        end.set_audio_chunks(end.audio_chunks() + 1);
        end.set_audio_frames(end.audio_frames() + c.audio().pcm_s16le().size() / 2 / c.audio().channels());
        break;
      case SessionChunk::kSyncEvent: end.set_sync_events(end.sync_events() + 1); break;
      default: break;
    }
  }
  ASSERT_TRUE(chunks.back().has_end());
  *chunks.back().mutable_end() = end;
}

std::size_t index_of(const std::vector<SessionChunk>& chunks, SessionChunk::ChunkCase kind, int n) {
  for (std::size_t i = 0; i < chunks.size(); ++i) {
    if (chunks[i].chunk_case() == kind && n-- == 0) return i;
  }
  ADD_FAILURE() << "fixture has no such chunk";
  return 0;
}

void validate_all(const std::vector<SessionChunk>& chunks) {
  SessionValidator validator;
  for (const SessionChunk& c : chunks) validator.check(c);
  validator.finish();
}

std::vector<SessionChunk> read_all(ChunkSource& source) {
  std::vector<SessionChunk> chunks;
  SessionChunk chunk;
  while (source.next(chunk)) chunks.push_back(chunk);
  return chunks;
}

void write_chunk_file(const std::filesystem::path& path, const std::vector<SessionChunk>& chunks) {
  ChunkFileWriter writer(path);
  for (const SessionChunk& c : chunks) writer.write(c);
  writer.finish();
}

std::vector<SessionChunk> read_chunk_file(const std::filesystem::path& path) {
  ChunkFileReader reader(path);
  return read_all(reader);
}

void expect_error(const std::function<void()>& action, ErrorCode code, const std::string& field) {
  try {
    action();
    ADD_FAILURE() << "expected an error on field '" << field << "', got none";
  } catch (const Error& e) {
    EXPECT_EQ(error_code_name(e.code()), std::string(error_code_name(code))) << e.what();
    EXPECT_EQ(e.field(), field) << e.what();
  }
}

void expect_same_stream(const std::vector<SessionChunk>& expected, const std::vector<SessionChunk>& actual) {
  ASSERT_EQ(expected.size(), actual.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    std::string diff;
    google::protobuf::util::MessageDifferencer differ;
    differ.ReportDifferencesToString(&diff);
    // Exact comparison, except that NaN (a missing mag reading) equals NaN.
    google::protobuf::util::DefaultFieldComparator comparator;
    comparator.set_treat_nan_as_equal(true);
    differ.set_field_comparator(&comparator);
    ASSERT_TRUE(differ.Compare(expected[i], actual[i])) << "chunk[" << i << "]: " << diff;
  }
}

TempDir::TempDir() {
  std::string pattern = (std::filesystem::temp_directory_path() / "posefuse_session_XXXXXX").string();
  if (!mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed");
  path_ = pattern;
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

}  // namespace posefuse::session::testing
