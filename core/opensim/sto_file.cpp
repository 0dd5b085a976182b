#include "opensim/sto_file.hpp"

#include <algorithm>
#include <map>
#include <vector>

#include "common/error.hpp"
#include "session/text_fields.hpp"

namespace posefuse::opensim {
namespace {

struct ImuColumn {
  std::string name;
  std::vector<std::int64_t> t_us;  // on the file's clock
  std::vector<Eigen::Quaterniond> G_from_A;
};

// W (x north, y west, z up) with y turned up: x north, y up, z east.
Eigen::Matrix3d north_ground_from_W() {
  Eigen::Matrix3d G_from_W;
  G_from_W << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  return G_from_W;
}

std::string column_name(const session::ResultDirectory& results, const std::string& device_id) {
  if (results.calibration) {
    for (const v1::ForearmModel& model : results.calibration->forearms()) {
      if (model.device_id() != device_id) continue;
      if (model.arm() == v1::RIGHT) return "radius_r_imu";
      if (model.arm() == v1::LEFT) return "radius_l_imu";
    }
  }
  return device_id;
}

Eigen::Quaterniond at(const ImuColumn& column, std::int64_t t_us) {
  const auto after = std::lower_bound(column.t_us.begin(), column.t_us.end(), t_us);
  const auto i = static_cast<std::size_t>(after - column.t_us.begin());
  if (i == 0) return column.G_from_A.front();
  if (i == column.t_us.size()) return column.G_from_A.back();
  const double span = static_cast<double>(column.t_us[i] - column.t_us[i - 1]);
  const double u = span > 0 ? static_cast<double>(t_us - column.t_us[i - 1]) / span : 0.0;
  return column.G_from_A[i - 1].slerp(u, column.G_from_A[i]).normalized();
}

std::string cell(Eigen::Quaterniond q) {
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  return session::format_double(q.w()) + "," + session::format_double(q.x()) + "," + session::format_double(q.y()) +
         "," + session::format_double(q.z());
}

}  // namespace

StoSummary write_sto(const session::ResultDirectory& results, const GroundFrame& ground, std::ostream& out) {
  if (results.imu_orientations.empty()) throw_precondition("imu_orientations", "the results have no IMU orientations");
  StoSummary summary;
  const std::optional<Eigen::Matrix3d> K_from_W_ = K_from_W(results);
  summary.camera_ground = K_from_W_.has_value();
  const Eigen::Matrix3d G_from_W =
      summary.camera_ground ? Eigen::Matrix3d(ground.G_from_K * *K_from_W_) : north_ground_from_W();
  summary.camera_clock = results.calibration.has_value();
  for (const auto& [device_id, samples] : results.imu_orientations) {
    if (!results.calibration || results.calibration->clock_offset_us().count(device_id) == 0)
      summary.camera_clock = false;
  }
  std::vector<ImuColumn> columns;
  for (const auto& [device_id, samples] : results.imu_orientations) {
    if (samples.empty()) continue;
    ImuColumn column{column_name(results, device_id), {}, {}};
    const std::int64_t offset_us = summary.camera_clock ? results.calibration->clock_offset_us().at(device_id) : 0;
    for (const session::TimedOrientation& s : samples) {
      column.t_us.push_back(s.t_us + offset_us);
      column.G_from_A.emplace_back(G_from_W * s.q.toRotationMatrix());
    }
    columns.push_back(std::move(column));
  }
  if (columns.empty()) throw_precondition("imu_orientations", "the results have no IMU orientations");
  std::int64_t first_us = columns.front().t_us.front(), last_us = columns.front().t_us.back();
  const ImuColumn* reference = &columns.front();
  for (const ImuColumn& column : columns) {
    first_us = std::max(first_us, column.t_us.front());
    last_us = std::min(last_us, column.t_us.back());
    if (column.t_us.size() > reference->t_us.size()) reference = &column;
  }
  std::vector<std::int64_t> times;
  for (const std::int64_t t : reference->t_us)
    if (t >= first_us && t <= last_us) times.push_back(t);
  if (times.empty()) throw_precondition("imu_orientations", "the IMUs' orientations share no span of time");
  summary.rows = times.size();
  summary.imus = columns.size();
  summary.rate_hz =
      times.size() > 1 ? static_cast<double>(times.size() - 1) * 1e6 / static_cast<double>(times.back() - times.front())
                       : 0.0;

  out << "DataRate=" << session::format_double(std::round(summary.rate_hz * 1000.0) / 1000.0)
      << "\nDataType=Quaternion\nversion=3\nOpenSimVersion=4.1\n"
      << "ground=" << (summary.camera_ground ? "camera" : "north")
      << "\nclock=" << (summary.camera_clock ? "camera" : "device") << "\nendheader\ntime";
  for (const ImuColumn& column : columns) out << '\t' << column.name;
  out << '\n';
  for (const std::int64_t t : times) {
    out << session::format_seconds(t);
    for (const ImuColumn& column : columns) out << '\t' << cell(at(column, t));
    out << '\n';
  }
  return summary;
}

}  // namespace posefuse::opensim
