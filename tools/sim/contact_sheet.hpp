#pragma once
// A contact sheet of a session for people: depth (colour-mapped), body index, the skeleton
// over the depth image, the RGB frame, and plots of every IMU's gyroscope, accelerometer and
// magnetometer over the whole session. ContactSheetRecorder sits between the simulator and the
// real sink, keeps the frame nearest `frame_t_us` and every IMU sample, and passes all chunks on.
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "imu/imu_sample.hpp"
#include "session/chunk_stream.hpp"

namespace posefuse::tools {

class ContactSheetRecorder : public session::ChunkSink {
 public:
  ContactSheetRecorder(session::ChunkSink& next, std::int64_t frame_t_us) : next_(next), frame_t_us_(frame_t_us) {}
  void write(const session::SessionChunk& chunk) override;
  void finish() override { next_.finish(); }

  // The sheet; kFailedPrecondition when no header or depth frame came.
  cv::Mat render() const;

 private:
  session::ChunkSink& next_;
  std::int64_t frame_t_us_;
  std::optional<v1::SessionHeader> header_;
  std::optional<v1::DepthFrame> depth_;
  std::optional<v1::BodyIndexFrame> body_index_;
  std::optional<v1::SkeletonFrame> skeleton_;
  std::optional<v1::ColorFrame> color_;
  std::map<std::string, std::vector<imu::ImuSample>> imu_;
};

// Writes `sheet` as PNG; kFailedPrecondition when that fails.
void write_png(const cv::Mat& sheet, const std::filesystem::path& path);

}  // namespace posefuse::tools
