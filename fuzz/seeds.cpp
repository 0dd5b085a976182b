#include "seeds.hpp"

#include <sys/mman.h>
#include <unistd.h>

#include <google/protobuf/stubs/logging.h>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <opencv2/core/utils/logger.hpp>
#include <opencv2/imgcodecs.hpp>

#include "session/image_codec.hpp"
#include "session/imu_batch.hpp"
#include "session/session_validator.hpp"

namespace posefuse::fuzz {

namespace {

constexpr int kWidth = 8;
constexpr int kHeight = 6;
constexpr std::int64_t kStartUs = 1'000'000;
constexpr std::int64_t kFrameUs = 33'333;

void set_intrinsics(v1::CameraIntrinsics* k, double f) {
  k->set_width(kWidth);
  k->set_height(kHeight);
  k->set_fx(f);
  k->set_fy(f);
  k->set_cx(3.5);
  k->set_cy(2.5);
}

cv::Mat gradient(int width, int height, int cv_type) {
  cv::Mat image(height, width, cv_type);
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      const int v = 40 * r + 9 * c;
      if (cv_type == CV_16UC1) image.at<std::uint16_t>(r, c) = static_cast<std::uint16_t>(1500 + v);
      else if (cv_type == CV_8UC1) image.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(v & 0xFF);
      else image.at<cv::Vec3b>(r, c) = cv::Vec3b(static_cast<std::uint8_t>(v), 90, 200);
    }
  }
  return image;
}

v1::SkeletonFrame skeleton(std::int64_t t_us) {
  v1::SkeletonFrame s;
  s.set_t_us(t_us);
  s.set_body_id(1);
  for (int j = 0; j < session::kSkeletonJointCount; ++j) {
    v1::SkeletonJoint* joint = s.add_joints();
    joint->mutable_position_m()->set_x(0.01 * j);
    joint->mutable_position_m()->set_y(0.5 - 0.04 * j);
    joint->mutable_position_m()->set_z(2.0);
    joint->set_state(v1::SkeletonJoint::TRACKED);
    joint->mutable_orientation()->set_w(1);
  }
  return s;
}

v1::ImuBatch imu_batch(const std::string& device, std::int64_t t0_us, int n) {
  std::vector<imu::ImuSample> samples(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    imu::ImuSample& s = samples[static_cast<std::size_t>(i)];
    s.t_us = t0_us + i * 10'000;
    s.gyr_rad_s = {0.1 * i, -0.1, 0.05};
    s.acc_m_s2 = {0.2, 0.1, 9.81};
    s.mag_uT = {21.5, -3.25, -40.0};
  }
  samples[1].mag_uT = imu::Vec3::Constant(std::nan(""));  // a missing mag reading
  return session::batch_from_samples(device, samples);
}

}  // namespace

v1::SessionHeader tiny_header() {
  v1::SessionHeader h;
  h.set_format_version(session::kFormatVersion);
  h.set_subject_id("S-fuzz");
  h.set_sex(v1::SessionHeader::FEMALE);
  h.set_height_m(1.7);
  const std::pair<const char*, v1::ImuDevice::Role> devices[] = {{"wrist_l", v1::ImuDevice::ARM_LEFT},
                                                                 {"base", v1::ImuDevice::BASE}};
  for (const auto& [id, role] : devices) {
    v1::ImuDevice* d = h.add_imu_devices();
    d->set_device_id(id);
    d->set_role(role);
    d->set_nominal_rate_hz(100);
  }
  set_intrinsics(h.mutable_depth_intrinsics(), 7.0);
  set_intrinsics(h.mutable_color_intrinsics(), 9.0);
  h.mutable_color_from_depth()->mutable_rotation()->set_w(1);
  h.mutable_color_from_depth()->mutable_translation_m()->set_x(-0.05);
  h.set_depth_rate_hz(30);
  h.set_color_rate_hz(30);
  h.set_audio_sample_rate_hz(16'000);
  h.set_audio_channels(1);
  (*h.mutable_options())["fit.enabled"] = "false";
  return h;
}

std::vector<v1::SessionChunk> tiny_session() {
  std::vector<v1::SessionChunk> chunks;
  *chunks.emplace_back().mutable_header() = tiny_header();
  const v1::DepthFrame::Encoding depth_encodings[] = {v1::DepthFrame::RAW_U16_LE, v1::DepthFrame::PNG16,
                                                      v1::DepthFrame::ZSTD_U16_LE};
  const v1::BodyIndexFrame::Encoding body_index_encodings[] = {v1::BodyIndexFrame::RAW_U8, v1::BodyIndexFrame::PNG8,
                                                               v1::BodyIndexFrame::ZSTD_U8};
  for (int f = 0; f < 3; ++f) {
    const std::int64_t t_us = kStartUs + f * kFrameUs;
    *chunks.emplace_back().mutable_depth() =
        session::encode_depth(gradient(kWidth, kHeight, CV_16UC1), depth_encodings[f], t_us);
    cv::Mat ids(kHeight, kWidth, CV_8UC1, cv::Scalar(255));
    ids(cv::Rect(2, 1, 3, 4)).setTo(1);
    *chunks.emplace_back().mutable_body_index() = session::encode_body_index(ids, body_index_encodings[f], t_us);
    *chunks.emplace_back().mutable_skeleton() = skeleton(t_us);
    v1::ColorFrame* color = chunks.emplace_back().mutable_color();
    color->set_t_us(t_us + 1'000);
    color->set_width(kWidth);
    color->set_height(kHeight);
    const bool jpeg = f == 1;
    color->set_encoding(jpeg ? v1::ColorFrame::JPEG : v1::ColorFrame::PNG);
    color->set_data(encoded_image(kWidth, kHeight, CV_8UC3, jpeg ? ".jpg" : ".png"));
  }
  *chunks.emplace_back().mutable_imu() = imu_batch("wrist_l", 990'000, 4);
  *chunks.emplace_back().mutable_imu() = imu_batch("base", 995'000, 3);
  v1::AudioChunk* audio = chunks.emplace_back().mutable_audio();
  audio->set_t_us(kStartUs);
  audio->set_sample_rate_hz(16'000);
  audio->set_channels(1);
  audio->set_pcm_s16le(std::string(64, '\x11'));
  v1::SyncEvent* sync = chunks.emplace_back().mutable_sync_event();
  sync->set_t_us(kStartUs + 5'000);
  sync->set_device_id("wrist_l");
  sync->set_kind(v1::SyncEvent::BLE_BROADCAST_RECEIPT);
  sync->set_payload("\x01\x02");
  v1::SyncEvent* buzz = chunks.emplace_back().mutable_sync_event();
  buzz->set_t_us(kStartUs + 6'000);
  buzz->set_device_id("camera");
  buzz->set_kind(v1::SyncEvent::BUZZER_STOP);

  session::SessionValidator validator;
  for (const v1::SessionChunk& chunk : chunks) validator.check(chunk);
  *chunks.emplace_back().mutable_end() = validator.counts();
  validator.check(chunks.back());
  validator.finish();
  return chunks;
}

std::string chunk_file_bytes(const std::vector<v1::SessionChunk>& chunks) {
  std::string out;
  for (const v1::SessionChunk& chunk : chunks) {
    const std::string body = chunk.SerializeAsString();
    std::uint64_t rest = body.size();
    do {
      const auto group = static_cast<char>(rest & 0x7F);
      rest >>= 7;
      out.push_back(static_cast<char>(group | (rest ? 0x80 : 0)));
    } while (rest);
    out += body;
  }
  return out;
}

std::string wav_bytes(std::uint16_t channels, std::uint32_t rate_hz, std::uint32_t frames) {
  std::string out;
  auto le32 = [&](std::uint32_t v) {
    for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
  };
  auto le16 = [&](std::uint16_t v) {
    out.push_back(static_cast<char>(v & 0xFF));
    out.push_back(static_cast<char>(v >> 8));
  };
  const std::uint32_t data_bytes = frames * 2u * channels;
  out += "RIFF";
  le32(36 + data_bytes);
  out += "WAVEfmt ";
  le32(16);
  le16(1);
  le16(channels);
  le32(rate_hz);
  le32(rate_hz * 2u * channels);
  le16(static_cast<std::uint16_t>(2 * channels));
  le16(16);
  out += "data";
  le32(data_bytes);
  for (std::uint32_t i = 0; i < data_bytes; ++i) out.push_back(static_cast<char>(i * 37));
  return out;
}

std::string encoded_image(int width, int height, int cv_type, const char* ext) {
  std::vector<unsigned char> bytes;
  if (!cv::imencode(ext, gradient(width, height, cv_type), bytes)) {
    invariant_failed(std::string("seed: cannot encode ") + ext);
  }
  return std::string(bytes.begin(), bytes.end());
}

void init_harness(const std::function<Seeds()>& make_seeds) {
  google::protobuf::SetLogHandler(nullptr);
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  const char* dir = std::getenv("POSEFUSE_FUZZ_WRITE_SEEDS");
  if (dir == nullptr || *dir == '\0') return;
  std::filesystem::create_directories(dir);
  int n = 0;
  for (const auto& [name, bytes] : make_seeds()) {
    std::ofstream out(std::filesystem::path(dir) / ("seed-" + name), std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) invariant_failed("seed: cannot write " + name);
    ++n;
  }
  std::printf("wrote %d seeds to %s\n", n, dir);
  std::exit(0);
}

int memory_file(const std::uint8_t* data, std::size_t size) {
  const int fd = ::memfd_create("fuzz-input", MFD_CLOEXEC);
  if (fd < 0) invariant_failed("memfd_create failed");
  std::size_t done = 0;
  while (done < size) {
    const ssize_t wrote = ::write(fd, data + done, size - done);
    if (wrote <= 0) invariant_failed("write to memfd failed");
    done += static_cast<std::size_t>(wrote);
  }
  if (::lseek(fd, 0, SEEK_SET) != 0) invariant_failed("lseek on memfd failed");
  return fd;
}

void invariant_failed(const std::string& what) {
  std::fprintf(stderr, "posefuse fuzz invariant failed: %s\n", what.c_str());
  std::abort();
}

}  // namespace posefuse::fuzz
