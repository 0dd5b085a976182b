#include "tools/sim/contact_sheet.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/error.hpp"
#include "raycast/depth_camera.hpp"
#include "session/image_codec.hpp"
#include "session/imu_batch.hpp"
#include "session/session_inputs.hpp"

namespace posefuse::tools {
namespace {

// Kinect v2 bones (JointType pairs) for the overlay.
const std::vector<std::pair<int, int>> kBones = {{0, 1},   {1, 20},  {20, 2},  {2, 3},   {20, 4},  {4, 5},
                                                 {5, 6},   {6, 7},   {7, 21},  {6, 22},  {20, 8},  {8, 9},
                                                 {9, 10},  {10, 11}, {11, 23}, {10, 24}, {0, 12},  {12, 13},
                                                 {13, 14}, {14, 15}, {0, 16},  {16, 17}, {17, 18}, {18, 19}};

std::int64_t distance(std::int64_t a, std::int64_t b) { return a > b ? a - b : b - a; }

template <typename Frame>
void keep_nearest(std::optional<Frame>& kept, const Frame& frame, std::int64_t target) {
  if (!kept || distance(frame.t_us(), target) < distance(kept->t_us(), target)) kept = frame;
}

void label(cv::Mat& image, const std::string& text) {
  cv::putText(image, text, {8, 22}, cv::FONT_HERSHEY_SIMPLEX, 0.6, {255, 255, 255}, 2);
  cv::putText(image, text, {8, 22}, cv::FONT_HERSHEY_SIMPLEX, 0.6, {0, 0, 0}, 1);
}

cv::Mat depth_view(const cv::Mat& depth_mm) {
  cv::Mat scaled, coloured;
  depth_mm.convertTo(scaled, CV_8U, 255.0 / 4500.0);
  cv::applyColorMap(scaled, coloured, cv::COLORMAP_JET);
  coloured.setTo(cv::Scalar(0, 0, 0), depth_mm == 0);
  return coloured;
}

// One channel group of one device over time: x red, y green, z blue.
cv::Mat plot(const std::vector<imu::ImuSample>& samples, int which, const std::string& title, int width, int height) {
  cv::Mat image(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  const auto value = [which](const imu::ImuSample& s) -> Eigen::Vector3d {
    return which == 0 ? s.gyr_rad_s : (which == 1 ? s.acc_m_s2 : s.mag_uT);
  };
  double low = 1e300, high = -1e300;
  for (const auto& s : samples) {
    const Eigen::Vector3d v = value(s);
    if (!v.allFinite()) continue;
    low = std::min(low, v.minCoeff());
    high = std::max(high, v.maxCoeff());
  }
  if (samples.size() < 2 || !(high >= low)) {
    label(image, title + " (no data)");
    return image;
  }
  if (high - low < 1e-9) {
    high += 1;
    low -= 1;
  }
  const double t0 = static_cast<double>(samples.front().t_us), t1 = static_cast<double>(samples.back().t_us);
  const int margin = 30;
  const auto point = [&](double t, double y) {
    return cv::Point(static_cast<int>(margin + (width - 2 * margin) * (t - t0) / std::max(1.0, t1 - t0)),
                     static_cast<int>(height - margin - (height - 2 * margin) * (y - low) / (high - low)));
  };
  const cv::Scalar colours[3] = {{0, 0, 220}, {0, 160, 0}, {220, 0, 0}};
  for (int axis = 0; axis < 3; ++axis) {
    for (std::size_t i = 1; i < samples.size(); ++i) {
      const double a = value(samples[i - 1])[axis], b = value(samples[i])[axis];
      if (!std::isfinite(a) || !std::isfinite(b)) continue;
      cv::line(image, point(static_cast<double>(samples[i - 1].t_us), a),
               point(static_cast<double>(samples[i].t_us), b), colours[axis], 1, cv::LINE_AA);
    }
  }
  char range[96];
  std::snprintf(range, sizeof range, "[%.3g, %.3g], %.1f s", low, high, (t1 - t0) * 1e-6);
  label(image, title + " " + range);
  return image;
}

}  // namespace

void ContactSheetRecorder::write(const session::SessionChunk& chunk) {
  switch (chunk.chunk_case()) {
    case v1::SessionChunk::kHeader: header_ = chunk.header(); break;
    case v1::SessionChunk::kDepth: keep_nearest(depth_, chunk.depth(), frame_t_us_); break;
    case v1::SessionChunk::kBodyIndex: keep_nearest(body_index_, chunk.body_index(), frame_t_us_); break;
    case v1::SessionChunk::kSkeleton: keep_nearest(skeleton_, chunk.skeleton(), frame_t_us_); break;
    case v1::SessionChunk::kColor: keep_nearest(color_, chunk.color(), frame_t_us_); break;
    case v1::SessionChunk::kImu: {
      auto samples = session::samples_from_batch(chunk.imu(), "imu");
      auto& all = imu_[chunk.imu().device_id()];
      all.insert(all.end(), samples.begin(), samples.end());
      break;
    }
    default: break;
  }
  next_.write(chunk);
}

cv::Mat ContactSheetRecorder::render() const {
  if (!header_ || !depth_) throw Error(ErrorCode::kFailedPrecondition, "contact_sheet", "no header or depth frame");
  const cv::Mat depth_mm = session::decode_depth(*depth_);
  const int h = depth_mm.rows;
  std::vector<cv::Mat> top;
  cv::Mat depth = depth_view(depth_mm);
  label(depth, "depth t=" + std::to_string(depth_->t_us() / 1000) + " ms");
  top.push_back(depth);
  if (body_index_) {
    const cv::Mat index = session::decode_body_index(*body_index_);
    cv::Mat view(index.size(), CV_8UC3, cv::Scalar(40, 40, 40));
    view.setTo(cv::Scalar(60, 200, 240), index != 255);
    label(view, "body index");
    top.push_back(view);
  }
  cv::Mat overlay, gray;
  depth_mm.convertTo(gray, CV_8U, 255.0 / 4500.0);
  cv::cvtColor(gray, overlay, cv::COLOR_GRAY2BGR);
  if (skeleton_) {
    const raycast::DepthCamera camera(session::pinhole_camera(header_->depth_intrinsics()));
    std::vector<std::optional<cv::Point>> pixels;
    for (const auto& joint : skeleton_->joints()) {
      const auto uv = camera.project({joint.position_m().x(), joint.position_m().y(), joint.position_m().z()});
      pixels.push_back(uv ? std::optional<cv::Point>(cv::Point(static_cast<int>(std::lround((*uv)[0])),
                                                               static_cast<int>(std::lround((*uv)[1]))))
                          : std::nullopt);
    }
    for (const auto& [a, b] : kBones) {
      if (pixels[static_cast<std::size_t>(a)] && pixels[static_cast<std::size_t>(b)]) {
        cv::line(overlay, *pixels[static_cast<std::size_t>(a)], *pixels[static_cast<std::size_t>(b)], {0, 220, 0}, 2);
      }
    }
    for (int j = 0; j < skeleton_->joints_size(); ++j) {
      if (!pixels[static_cast<std::size_t>(j)]) continue;
      const bool tracked = skeleton_->joints(j).state() == v1::SkeletonJoint::TRACKED;
      cv::circle(overlay, *pixels[static_cast<std::size_t>(j)], 3,
                 tracked ? cv::Scalar(0, 255, 255) : cv::Scalar(0, 0, 255), -1);
    }
  }
  label(overlay, "skeleton (yellow tracked, red inferred)");
  top.push_back(overlay);
  if (color_) {
    const std::string& bytes = color_->data();
    cv::Mat colour = cv::imdecode(cv::Mat(1, static_cast<int>(bytes.size()), CV_8U, const_cast<char*>(bytes.data())),
                                  cv::IMREAD_COLOR);
    if (!colour.empty()) {
      cv::resize(colour, colour, {static_cast<int>(std::lround(colour.cols * static_cast<double>(h) / colour.rows)), h},
                 0, 0, cv::INTER_AREA);
      label(colour, "RGB");
      top.push_back(colour);
    }
  }
  cv::Mat sheet;
  cv::hconcat(top, sheet);
  const int plot_width = sheet.cols / 3;
  for (const auto& [device, samples] : imu_) {
    std::vector<cv::Mat> row;
    row.push_back(plot(samples, 0, device + " gyr rad/s", plot_width, 170));
    row.push_back(plot(samples, 1, device + " acc m/s2", plot_width, 170));
    row.push_back(plot(samples, 2, device + " mag uT", sheet.cols - 2 * plot_width, 170));
    cv::Mat line;
    cv::hconcat(row, line);
    cv::vconcat(sheet, line, sheet);
  }
  return sheet;
}

void write_png(const cv::Mat& sheet, const std::filesystem::path& path) {
  if (!cv::imwrite(path.string(), sheet, {cv::IMWRITE_PNG_COMPRESSION, 9})) {
    throw Error(ErrorCode::kFailedPrecondition, path.string(), "cannot write the PNG");
  }
}

}  // namespace posefuse::tools
