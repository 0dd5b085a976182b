#include "tools/sim/calibration_capture_files.hpp"

#include <algorithm>
#include <cstdio>
#include <map>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include "common/error.hpp"
#include "session/file_bytes.hpp"
#include "session/stages/forearm_options.hpp"
#include "session/text_fields.hpp"
#include "sim/ground_truth_files.hpp"

namespace posefuse::tools {

namespace {

namespace fs = std::filesystem;
using geometry::Quat;
using geometry::Vec3;
using session::format_double;
constexpr double kDeg = 3.14159265358979323846 / 180.0;

std::string image_name(std::size_t pose, const char* kind) {
  return "pose_" + std::to_string(pose) + "_" + kind + ".png";
}

void write_png16(const std::vector<std::uint16_t>& pixels, const geometry::PinholeCamera& camera,
                 const fs::path& path) {
  const cv::Mat image(camera.height, camera.width, CV_16UC1, const_cast<std::uint16_t*>(pixels.data()));
  if (!cv::imwrite(path.string(), image)) throw Error(ErrorCode::kInternal, path.string(), "could not write the PNG");
}

std::vector<std::uint16_t> read_png16(const fs::path& path, const geometry::PinholeCamera& camera) {
  if (!fs::is_regular_file(path)) throw Error(ErrorCode::kNotFound, path.string(), "missing");
  const cv::Mat image = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  if (image.empty()) throw Error(ErrorCode::kNotFound, path.string(), "missing or not an image");
  if (image.type() != CV_16UC1 || image.cols != camera.width || image.rows != camera.height) {
    throw_invalid(path.string(), "must be a 16-bit single-channel " + std::to_string(camera.width) + "x" +
                                     std::to_string(camera.height) + " PNG");
  }
  std::vector<std::uint16_t> out(static_cast<std::size_t>(camera.width) * static_cast<std::size_t>(camera.height));
  for (int row = 0; row < image.rows; ++row) {
    std::copy_n(image.ptr<std::uint16_t>(row), camera.width,
                out.begin() + static_cast<std::ptrdiff_t>(row) * camera.width);
  }
  return out;
}

// Data lines of a CSV with a fixed header, split at commas; `where` is "file:line".
std::vector<std::pair<std::string, std::vector<std::string>>> csv_rows(const fs::path& path,
                                                                       const std::string& header) {
  std::istringstream in(session::read_file_bytes(path, path.string()));
  std::string line;
  if (!std::getline(in, line) || line != header) throw_invalid(path.string() + ":1", "header must be '" + header + "'");
  std::vector<std::pair<std::string, std::vector<std::string>>> rows;
  const std::size_t columns = static_cast<std::size_t>(std::count(header.begin(), header.end(), ',')) + 1;
  for (int number = 2; std::getline(in, line); ++number) {
    if (line.empty()) continue;
    std::vector<std::string> cells;
    std::stringstream cells_in(line);
    for (std::string cell; std::getline(cells_in, cell, ',');) cells.push_back(cell);
    const std::string where = path.string() + ":" + std::to_string(number);
    if (cells.size() != columns)
      throw_invalid(where, std::to_string(cells.size()) + " columns, expected " + std::to_string(columns));
    rows.emplace_back(where, std::move(cells));
  }
  return rows;
}

std::size_t pose_index(const std::string& text, const std::string& where, std::size_t poses) {
  const std::uint64_t pose = session::parse_uint64(text, where + ":pose");
  if (pose >= poses)
    throw_invalid(where + ":pose", "is " + text + ", capture.txt has " + std::to_string(poses) + " poses");
  return static_cast<std::size_t>(pose);
}

const char* const kMarkersHeader = "pose,marker,x_m,y_m,z_m";
const char* const kImuHeader = "pose,device,t_us,gx_rad_s,gy_rad_s,gz_rad_s,ax_m_s2,ay_m_s2,az_m_s2,mx_uT,my_uT,mz_uT";

std::string quat_text(const Quat& q) {
  return format_double(q.w()) + " " + format_double(q.x()) + " " + format_double(q.y()) + " " + format_double(q.z());
}

// preview.png: per pose (columns) the IR image (gamma 0.4, markers white) above the depth
// (near bright, no reading black, 4.5 m dark).
void write_preview(const calib::CalibrationCapture& capture, const fs::path& path) {
  const int w = capture.camera.width, h = capture.camera.height;
  cv::Mat sheet(2 * h, w * static_cast<int>(capture.poses.size()), CV_8UC1, cv::Scalar(0));
  for (std::size_t i = 0; i < capture.poses.size(); ++i) {
    const calib::CapturePose& pose = capture.poses[i];
    for (int row = 0; row < h; ++row) {
      for (int col = 0; col < w; ++col) {
        const std::size_t p =
            static_cast<std::size_t>(row) * static_cast<std::size_t>(w) + static_cast<std::size_t>(col);
        const int x = static_cast<int>(i) * w + col;
        sheet.at<std::uint8_t>(row, x) = cv::saturate_cast<std::uint8_t>(255.0 * std::pow(pose.ir[p] / 65535.0, 0.4));
        const double z = pose.depth_mm[p];
        sheet.at<std::uint8_t>(h + row, x) =
            z == 0 ? 0 : cv::saturate_cast<std::uint8_t>(40 + 215 * (1.0 - z / 4500.0));
      }
    }
  }
  if (!cv::imwrite(path.string(), sheet)) throw Error(ErrorCode::kInternal, path.string(), "could not write the PNG");
}

}  // namespace

void write_calibration_capture(const sim::PanelCaptureResult& result, const fs::path& directory) {
  fs::create_directories(directory);
  const calib::CalibrationCapture& capture = result.capture;
  const geometry::PinholeCamera& c = capture.camera;
  std::string text = "# posefuse calibration-panel capture (docs/simulator.md)\n";
  for (const auto& [key, value] :
       std::vector<std::pair<std::string, double>>{{"width", c.width},
                                                   {"height", c.height},
                                                   {"fx", c.fx},
                                                   {"fy", c.fy},
                                                   {"cx", c.cx},
                                                   {"cy", c.cy},
                                                   {"k1", c.k1},
                                                   {"k2", c.k2},
                                                   {"k3", c.k3},
                                                   {"poses", static_cast<double>(capture.poses.size())}}) {
    text += key + " = " + format_double(value) + "\n";
  }
  session::write_file_bytes(directory / "capture.txt", text);
  std::string markers = std::string(kMarkersHeader) + "\n", imu = std::string(kImuHeader) + "\n";
  for (std::size_t i = 0; i < capture.poses.size(); ++i) {
    const calib::CapturePose& pose = capture.poses[i];
    write_png16(pose.ir, c, directory / image_name(i, "ir"));
    write_png16(pose.depth_mm, c, directory / image_name(i, "depth"));
    for (std::size_t m = 0; m < 4; ++m) {
      const Vec3& p = pose.markers_E[m];
      markers += std::to_string(i) + "," + std::to_string(m) + "," + format_double(p.x()) + "," + format_double(p.y()) +
                 "," + format_double(p.z()) + "\n";
    }
    for (const auto& [device, samples] : {std::pair{"panel", &pose.panel_imu}, std::pair{"base", &pose.base_imu}}) {
      for (const imu::ImuSample& s : *samples) {
        imu += std::to_string(i) + "," + device + "," + std::to_string(s.t_us);
        for (const Vec3* v : {&s.gyr_rad_s, &s.acc_m_s2, &s.mag_uT}) {
          for (int k = 0; k < 3; ++k) imu += "," + format_double((*v)[k]);
        }
        imu += "\n";
      }
    }
  }
  write_preview(capture, directory / "preview.png");
  session::write_file_bytes(directory / "markers.csv", markers);
  session::write_file_bytes(directory / "imu.csv", imu);
  const sim::PanelCaptureTruth& t = result.truth;
  std::string json =
      "{\n  \"K_from_E\": " + sim::json_quat(t.K_from_E) + ",\n  \"E_origin_K\": " + sim::json_vec(t.E_origin_K) +
      ",\n  \"K_from_B\": " + sim::json_quat(t.K_from_B) + ",\n  \"K_from_W\": " + sim::json_quat(t.K_from_W) +
      ",\n  \"P_from_panel_imu\": " + sim::json_quat(t.P_from_panel_imu) +
      ",\n  \"marker_noise_m\": " + format_double(t.marker_noise_m) + ",\n  \"poses\": [";
  for (std::size_t i = 0; i < t.K_from_P.size(); ++i) {
    json += std::string(i ? "," : "") + "\n    {\"K_from_P\": " + sim::json_quat(t.K_from_P[i].X_from_P) +
            ", \"P_origin_K\": " + sim::json_vec(t.K_from_P[i].origin_X) + "}";
  }
  json += "\n  ],\n  \"panel_imu_acc_bias_m_s2\": " + sim::json_vec(t.panel_imu_errors.acc_bias_m_s2) +
          ",\n  \"base_imu_acc_bias_m_s2\": " + sim::json_vec(t.base_imu_errors.acc_bias_m_s2) + "\n}\n";
  session::write_file_bytes(directory / "truth.json", json);
}

calib::CalibrationCapture read_calibration_capture(const fs::path& directory) {
  const fs::path header_path = directory / "capture.txt";
  std::map<std::string, double> values;
  {
    std::istringstream in(session::read_file_bytes(header_path, header_path.string()));
    std::string line;
    for (int number = 1; std::getline(in, line); ++number) {
      if (line.empty() || line[0] == '#') continue;
      const auto equals = line.find(" = ");
      const std::string where = header_path.string() + ":" + std::to_string(number);
      if (equals == std::string::npos) throw_invalid(where, "expected 'key = value', got '" + line + "'");
      values[line.substr(0, equals)] = session::parse_double(line.substr(equals + 3), where);
    }
  }
  const auto value = [&](const std::string& key) {
    const auto it = values.find(key);
    if (it == values.end()) throw_invalid(header_path.string() + ":" + key, "missing");
    return it->second;
  };
  calib::CalibrationCapture capture;
  capture.camera = {static_cast<int>(value("width")),
                    static_cast<int>(value("height")),
                    value("fx"),
                    value("fy"),
                    value("cx"),
                    value("cy"),
                    value("k1"),
                    value("k2"),
                    value("k3"),
                    0.0,
                    0.0};
  geometry::validate(capture.camera, header_path.string());
  const double poses = value("poses");
  if (!(poses >= 0 && poses <= 1000) || poses != std::floor(poses)) {
    throw_invalid(header_path.string() + ":poses", "must be a whole number 0..1000");
  }
  capture.poses.resize(static_cast<std::size_t>(poses));
  for (std::size_t i = 0; i < capture.poses.size(); ++i) {
    capture.poses[i].ir = read_png16(directory / image_name(i, "ir"), capture.camera);
    capture.poses[i].depth_mm = read_png16(directory / image_name(i, "depth"), capture.camera);
  }
  std::vector<std::array<bool, 4>> have(capture.poses.size(), {false, false, false, false});
  for (const auto& [where, cells] : csv_rows(directory / "markers.csv", kMarkersHeader)) {
    const std::size_t pose = pose_index(cells[0], where, capture.poses.size());
    const std::uint64_t marker = session::parse_uint64(cells[1], where + ":marker");
    if (marker > 3) throw_invalid(where + ":marker", "is " + cells[1] + ", must be 0..3");
    capture.poses[pose].markers_E[marker] =
        Vec3(session::parse_double(cells[2], where + ":x_m"), session::parse_double(cells[3], where + ":y_m"),
             session::parse_double(cells[4], where + ":z_m"));
    have[pose][marker] = true;
  }
  for (std::size_t i = 0; i < have.size(); ++i) {
    for (std::size_t m = 0; m < 4; ++m) {
      if (!have[i][m])
        throw_invalid((directory / "markers.csv").string(),
                      "pose " + std::to_string(i) + " has no marker " + std::to_string(m));
    }
  }
  for (const auto& [where, cells] : csv_rows(directory / "imu.csv", kImuHeader)) {
    calib::CapturePose& pose = capture.poses[pose_index(cells[0], where, capture.poses.size())];
    if (cells[1] != "panel" && cells[1] != "base")
      throw_invalid(where + ":device", "is '" + cells[1] + "', expected panel or base");
    imu::ImuSample s;
    s.t_us = session::parse_int64(cells[2], where + ":t_us");
    std::array<Vec3*, 3> vectors = {&s.gyr_rad_s, &s.acc_m_s2, &s.mag_uT};
    for (std::size_t k = 0; k < 9; ++k) {
      (*vectors[k / 3])[static_cast<Eigen::Index>(k % 3)] =
          session::parse_double(cells[3 + k], where + ":" + std::to_string(k + 3));
    }
    (cells[1] == "panel" ? pose.panel_imu : pose.base_imu).push_back(s);
  }
  return capture;
}

calib::CaptureCalibration calibrate_capture_directory(const fs::path& directory) {
  const calib::CalibrationCapture capture = read_calibration_capture(directory);
  try {
    return calib::calibrate_capture(capture);
  } catch (const Error& error) {
    // "poses[2].ir" -> the file that shows it.
    const std::string& field = error.field();
    const std::string message = std::string(error.what()).substr(field.size() + 2);
    std::size_t pose = 0;
    char rest[64] = {};
    if (std::sscanf(field.c_str(), "poses[%zu].%63s", &pose, rest) == 2) {
      const std::string part = rest;
      const fs::path file = part.rfind("ir", 0) == 0                ? directory / image_name(pose, "ir")
                            : part.rfind("depth", 0) == 0           ? directory / image_name(pose, "depth")
                            : part.find("imu") != std::string::npos ? directory / "imu.csv"
                                                                    : directory / image_name(pose, "ir");
      throw Error(error.code(), file.string() + ": " + part, message);
    }
    const fs::path file = field.rfind("mocap", 0) == 0 || field.rfind("markers", 0) == 0 ? directory / "markers.csv"
                          : field == "readings"                                          ? directory / "imu.csv"
                                                                                         : directory;
    throw Error(error.code(), file.string() + ": " + field, message);
  }
}

std::string calibration_report(const calib::CaptureCalibration& r) {
  std::string out;
  char line[256];
  for (std::size_t i = 0; i < r.poses.size(); ++i) {
    const calib::PanelInCamera& seen = r.poses[i].seen;
    std::snprintf(line, sizeof line,
                  "pose %zu: panel at %.3f m, board RMS %.2f mm, axis skew %.2f deg, X/Y gap %.2f mm, markers %.2f px, "
                  "points x/y/board %d/%d/%d\n",
                  i, seen.pose.origin_X.norm(), 1e3 * seen.board_rms_m, seen.axis_skew_rad / kDeg,
                  1e3 * seen.intersection_gap_m, seen.marker_residual_px, seen.x_points, seen.y_points,
                  seen.board_points);
    out += line;
  }
  std::snprintf(line, sizeof line, "panel turned up to %.1f deg between poses\n", r.pose_spread_rad / kDeg);
  out += line;
  out += "K_from_E (w x y z) = " + quat_text(r.mocap.K_from_E) + "   (eq. 4)\n";
  out += "E_origin_K (m) = " + format_double(r.mocap.E_origin_K.x()) + " " + format_double(r.mocap.E_origin_K.y()) +
         " " + format_double(r.mocap.E_origin_K.z()) + "   (eq. 5)\n";
  std::snprintf(line, sizeof line, "mocap markers reprojected: %.2f px RMS over %d poses\n", r.mocap.marker_residual_px,
                r.mocap.poses);
  out += line;
  out += "K_from_B (w x y z) = " + quat_text(r.base.K_from_B) + "   (eq. 8)\n";
  std::snprintf(line, sizeof line, "eq. 8 spread over %d readings: %.2f deg RMS\n", r.base.readings,
                r.base.spread_rad / kDeg);
  out += line;
  out += "K_from_W (w x y z) = " + quat_text(r.K_from_W) + "   (eq. 7, mean base IMU orientation of the capture)\n";
  out += std::string(session::kForearmKFromBKey) + " = " + quat_text(r.base.K_from_B) + "\n";
  return out;
}

}  // namespace posefuse::tools
