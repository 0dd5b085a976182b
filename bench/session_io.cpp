// Session I/O speed: a 10 s synthetic recording (512x424 depth and body index at 30 Hz,
// skeletons, three IMUs at 80 Hz) written and read back as a chunk file per depth encoding,
// with and without validation, and through the directory form.
//
//   build/bench/bench_session_io [seconds=10]
//
// Prints one row per case: size on disk, seconds, and recorded seconds per wall second
// (> 1 means faster than real time).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

#include <opencv2/core.hpp>

#include "session/chunk_file.hpp"
#include "session/convert.hpp"
#include "session/directory_reader.hpp"
#include "session/image_codec.hpp"
#include "session/imu_batch.hpp"
#include "session/session_validator.hpp"

namespace {

using namespace posefuse;
using namespace posefuse::session;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

std::uint64_t disk_bytes(const std::filesystem::path& path) {
  if (std::filesystem::is_regular_file(path)) return std::filesystem::file_size(path);
  std::uint64_t total = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(path)) {
    if (entry.is_regular_file()) total += entry.file_size();
  }
  return total;
}

v1::SessionHeader make_header() {
  v1::SessionHeader h;
  h.set_format_version(kFormatVersion);
  h.set_subject_id("bench");
  for (const char* id : {"wrist_l", "wrist_r", "base"}) {
    v1::ImuDevice* d = h.add_imu_devices();
    d->set_device_id(id);
    d->set_role(std::string(id) == "base" ? v1::ImuDevice::BASE : v1::ImuDevice::ARM_LEFT);
    d->set_nominal_rate_hz(80);
  }
  auto* k = h.mutable_depth_intrinsics();
  k->set_width(512);
  k->set_height(424);
  k->set_fx(365.0);
  k->set_fy(365.0);
  k->set_cx(256.0);
  k->set_cy(212.0);
  h.set_depth_rate_hz(30);
  return h;
}

// A wall at 3 m with a person-sized blob at 2 m, plus sensor-like noise and holes.
void make_frame(int f, cv::Mat& depth, cv::Mat& ids, cv::RNG& rng) {
  depth.create(424, 512, CV_16UC1);
  ids.create(424, 512, CV_8UC1);
  const double cx = 256 + 60 * std::sin(f * 0.05);
  for (int r = 0; r < 424; ++r) {
    auto* d = depth.ptr<std::uint16_t>(r);
    auto* b = ids.ptr<std::uint8_t>(r);
    for (int c = 0; c < 512; ++c) {
      const bool body = std::abs(c - cx) < 60 && r > 60 && r < 400;
      const double mm = (body ? 2000.0 : 3000.0) + rng.gaussian(4.0);
      d[c] = (r * 7 + c * 13 + f) % 97 == 0 ? 0 : static_cast<std::uint16_t>(mm);
      b[c] = body ? 0 : 255;
    }
  }
}

std::vector<v1::SessionChunk> make_session(double seconds, v1::DepthFrame::Encoding encoding) {
  std::vector<v1::SessionChunk> chunks;
  *chunks.emplace_back().mutable_header() = make_header();
  cv::RNG rng(7);
  cv::Mat depth, ids;
  const int frames = static_cast<int>(seconds * 30);
  const int imu_per_frame = 8;  // batches of ~3 frames' worth, 80 Hz
  std::vector<imu::ImuSample> pending[3];
  v1::EndOfSession end;
  for (int f = 0; f < frames; ++f) {
    const std::int64_t t = 33'333LL * f;
    make_frame(f, depth, ids, rng);
    *chunks.emplace_back().mutable_depth() = encode_depth(depth, encoding, t);
    *chunks.emplace_back().mutable_body_index() = encode_body_index(ids, v1::BodyIndexFrame::PNG8, t);
    v1::SkeletonFrame* s = chunks.emplace_back().mutable_skeleton();
    s->set_t_us(t);
    for (int j = 0; j < 25; ++j) {
      auto* joint = s->add_joints();
      joint->set_state(v1::SkeletonJoint::TRACKED);
      joint->mutable_position_m()->set_z(2.0);
      joint->mutable_orientation()->set_w(1.0);
    }
    end.set_depth_frames(end.depth_frames() + 1);
    end.set_body_index_frames(end.body_index_frames() + 1);
    end.set_skeleton_frames(end.skeleton_frames() + 1);
    for (int d = 0; d < 3; ++d) {
      // 80 Hz: 8 samples per 3 frames.
      const std::int64_t first = (f * 8) / 3, last = ((f + 1) * 8) / 3;
      for (std::int64_t i = first; i < last; ++i) {
        imu::ImuSample sample;
        sample.t_us = i * 12'500;
        sample.acc_m_s2 = {0, 0, 9.81};
        sample.mag_uT = {20, 0, -40};
        pending[d].push_back(sample);
      }
      if (static_cast<int>(pending[d].size()) >= imu_per_frame * 4 || f == frames - 1) {
        const std::string id = chunks[0].header().imu_devices(d).device_id();
        (*end.mutable_imu_samples())[id] += pending[d].size();
        *chunks.emplace_back().mutable_imu() = batch_from_samples(id, pending[d]);
        pending[d].clear();
      }
    }
  }
  *chunks.emplace_back().mutable_end() = end;
  return chunks;
}

void row(const char* what, const char* encoding, std::uint64_t bytes, double wall_s, double recorded_s) {
  std::printf("| %-32s | %-11s | %8.1f | %7.3f | %8.1f |\n", what, encoding, bytes / 1048576.0, wall_s,
              recorded_s / wall_s);
}

}  // namespace

int main(int argc, char** argv) {
  const double seconds = argc > 1 ? std::atof(argv[1]) : 10.0;
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("posefuse_session_bench_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  std::printf("session I/O, %.0f s recording, 512x424 depth + body index at 30 Hz, 3 IMUs at 80 Hz\n", seconds);
  std::printf("| %-32s | %-11s | %8s | %7s | %8s |\n", "case", "depth", "MiB", "s", "x realtime");
  std::printf("|---|---|---|---|---|\n");
  for (const auto encoding : {v1::DepthFrame::RAW_U16_LE, v1::DepthFrame::PNG16, v1::DepthFrame::ZSTD_U16_LE}) {
    const char* name = v1::DepthFrame::Encoding_Name(encoding).c_str();
    auto start = Clock::now();
    const auto chunks = make_session(seconds, encoding);
    row("generate + encode", name, 0, seconds_since(start), seconds);

    const auto file = dir / (std::string(name) + ".pfchunks");
    start = Clock::now();
    {
      ChunkFileWriter writer(file);
      for (const auto& c : chunks) writer.write(c);
      writer.finish();
    }
    row("write chunk file", name, disk_bytes(file), seconds_since(start), seconds);

    start = Clock::now();
    std::uint64_t n = 0;
    {
      ChunkFileReader reader(file);
      v1::SessionChunk chunk;
      while (reader.next(chunk)) ++n;
    }
    row("read chunk file", name, disk_bytes(file), seconds_since(start), seconds);

    start = Clock::now();
    {
      ChunkFileReader reader(file);
      SessionValidator validator;
      v1::SessionChunk chunk;
      while (reader.next(chunk)) validator.check(chunk);
      validator.finish();
    }
    row("read + validate chunk file", name, disk_bytes(file), seconds_since(start), seconds);

    const auto rec = dir / (std::string(name) + "_dir");
    start = Clock::now();
    chunk_file_to_directory(file, rec);
    row("chunk file -> directory (valid.)", name, disk_bytes(rec), seconds_since(start), seconds);

    start = Clock::now();
    {
      DirectoryReader reader(rec);
      v1::SessionChunk chunk;
      while (reader.next(chunk)) ++n;
    }
    row("read directory", name, disk_bytes(rec), seconds_since(start), seconds);
  }
  std::filesystem::remove_all(dir);
  return 0;
}
