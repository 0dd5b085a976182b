#include "opensim/trc_file.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include "body/smpl_model.hpp"
#include "common/error.hpp"
#include "geometry/kinect_joints.hpp"
#include "session/frame_merge.hpp"
#include "session/text_fields.hpp"

namespace posefuse::opensim {
namespace {

struct MarkerFrame {
  std::int64_t t_us = 0;
  std::vector<std::optional<Eigen::Vector3d>> p_G;  // one per marker
};

// Rows come one frame after another (result_reader checks that t_us never goes back).
std::vector<MarkerFrame> marker_frames(const std::vector<session::JointRow>& joints, std::size_t markers,
                                       const GroundFrame& ground) {
  std::vector<MarkerFrame> frames;
  for (const session::JointRow& row : joints) {
    if (frames.empty() || frames.back().t_us != row.t_us)
      frames.push_back({row.t_us, std::vector<std::optional<Eigen::Vector3d>>(markers)});
    if (row.confidence > session::kLostFitConfidence && row.joint >= 0 && static_cast<std::size_t>(row.joint) < markers)
      frames.back().p_G[static_cast<std::size_t>(row.joint)] = ground.point_G(row.p_K);
  }
  return frames;
}

double median_interval_s(const std::vector<MarkerFrame>& frames) {
  std::vector<std::int64_t> dt;
  for (std::size_t i = 1; i < frames.size(); ++i) dt.push_back(frames[i].t_us - frames[i - 1].t_us);
  std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2), dt.end());
  return static_cast<double>(dt[dt.size() / 2]) * 1e-6;
}

std::string number(double value) { return std::isfinite(value) ? session::format_double(value) : "NaN"; }

}  // namespace

TrcSummary write_trc(const session::ResultDirectory& results, const GroundFrame& ground, const std::string& file_name,
                     std::ostream& out) {
  const bool smpl = !results.smpl_joints.empty();
  const std::size_t markers = smpl ? static_cast<std::size_t>(body::kNumJoints) : geometry::kKinectJointCount;
  const char* const* names = smpl ? body::smpl_joint_names().data() : geometry::kKinectJointNames.data();
  const std::vector<MarkerFrame> frames = marker_frames(marker_joints(results), markers, ground);
  if (frames.size() < 2)
    throw_precondition(smpl ? "smpl_joints.csv" : "camera_joints.csv",
                       "a marker file needs at least two frames; the results have " + std::to_string(frames.size()));
  TrcSummary summary;
  summary.frames = frames.size();
  summary.markers = markers;
  summary.rate_hz = 1.0 / median_interval_s(frames);

  const std::string rate = session::format_double(std::round(summary.rate_hz * 1000.0) / 1000.0);
  const std::string frame_count = std::to_string(frames.size());
  out << "PathFileType\t4\t(X/Y/Z)\t" << file_name << "\n";
  out << "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame\tOrigNumFrames\n";
  out << rate << '\t' << rate << '\t' << frame_count << '\t' << markers << "\tm\t" << rate << "\t1\t" << frame_count
      << "\n";
  out << "Frame#\tTime";
  for (std::size_t m = 0; m < markers; ++m) out << '\t' << names[m] << "\t\t";
  out << "\n\t";
  for (std::size_t m = 1; m <= markers; ++m) out << "\tX" << m << "\tY" << m << "\tZ" << m;
  out << "\n\n";
  for (std::size_t f = 0; f < frames.size(); ++f) {
    out << f + 1 << '\t' << session::format_seconds(frames[f].t_us);
    for (const std::optional<Eigen::Vector3d>& p : frames[f].p_G) {
      if (!p) ++summary.missing;
      const Eigen::Vector3d v = p.value_or(Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
      out << '\t' << number(v.x()) << '\t' << number(v.y()) << '\t' << number(v.z());
    }
    out << '\n';
  }
  return summary;
}

}  // namespace posefuse::opensim
