// `posefuse-sim calibrate DIR`'s pieces: a simulated calibration-panel capture written as
// calibration_capture/, read back and calibrated, gives exactly the in-memory calibration (PNG
// and the CSVs' shortest exact numbers are lossless); refusals name the file.
#include <gtest/gtest.h>

#include <algorithm>

#include "../imu/expect_error.hpp"
#include "../scratch_dir.hpp"
#include "session/file_bytes.hpp"
#include "sim/room_frame.hpp"
#include "tools/sim/calibration_capture_files.hpp"
#include "tools/sim/sim_run.hpp"

using namespace posefuse;
using posefuse::testing::expect_error;
namespace fs = std::filesystem;

namespace {

fs::path fresh_dir(const std::string& name) {
  return posefuse::testing::fresh_scratch_dir("posefuse_calibration_capture_test", name);
}

sim::PanelCaptureRig rig() {
  sim::PanelCaptureRig r;
  const sim::Quat K_from_Body(Eigen::AngleAxisd(3.14159265358979323846, sim::Vec3::UnitY()));
  r.K_from_W = (K_from_Body * sim::W_from_R(0.3).conjugate()).normalized();
  sim::Mat3 K_from_B;
  K_from_B << 0, 1, 0, 0, 0, 1, 1, 0, 0;
  r.K_from_B = sim::Quat(K_from_B);
  r.seed = 7;
  return r;
}

TEST(CalibrationCaptureFiles, TheWrittenFolderCalibratesExactlyAsInMemory) {
  const sim::PanelCaptureResult capture = sim::simulate_panel_capture({}, rig());
  const fs::path dir = fresh_dir("good");
  tools::write_calibration_capture(capture, dir);
  for (const char* file :
       {"capture.txt", "markers.csv", "imu.csv", "truth.json", "pose_0_ir.png", "pose_3_depth.png"}) {
    EXPECT_TRUE(fs::exists(dir / file)) << file;
  }
  const calib::CaptureCalibration in_memory = calib::calibrate_capture(capture.capture);
  const calib::CaptureCalibration from_files = tools::calibrate_capture_directory(dir);
  EXPECT_EQ(from_files.base.K_from_B.coeffs(), in_memory.base.K_from_B.coeffs());
  EXPECT_EQ(from_files.mocap.K_from_E.coeffs(), in_memory.mocap.K_from_E.coeffs());
  EXPECT_EQ(from_files.mocap.E_origin_K, in_memory.mocap.E_origin_K);
  // Against the truth: the bounds of tests/sim/panel_capture_test.cpp (derived there).
  EXPECT_LT(geometry::angle_between(from_files.mocap.K_from_E, capture.truth.K_from_E), 0.7 * 3.14159265358979 / 180);
  const std::string report = tools::calibration_report(from_files);
  std::printf("%s", report.c_str());
  EXPECT_NE(report.find("forearm.K_from_B = "), std::string::npos);
}

TEST(CalibrationCaptureFiles, RefusalsNameTheFile) {
  sim::PanelCaptureOptions options;
  options.poses_K = sim::simulate_panel_capture(options, rig()).truth.K_from_P;
  options.poses_K[1].origin_X += sim::Vec3(3.0, 0.0, 0.0);  // out of view
  const fs::path dir = fresh_dir("away");
  tools::write_calibration_capture(sim::simulate_panel_capture(options, rig()), dir);
  expect_error([&] { tools::calibrate_capture_directory(dir); }, ErrorCode::kFailedPrecondition,
               (dir / "pose_1_ir.png").string() + ": ir", "expected the panel's 4 markers");
  // A truncated marker file and a missing image.
  std::string markers = session::read_file_bytes(dir / "markers.csv", "markers.csv");
  session::write_file_bytes(dir / "markers.csv", markers.substr(0, markers.size() - 20));
  try {
    tools::calibrate_capture_directory(dir);
    ADD_FAILURE() << "a truncated markers.csv was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument) << e.what();
    EXPECT_NE(e.field().find("markers.csv"), std::string::npos) << e.what();
  }
  session::write_file_bytes(dir / "markers.csv", markers);
  fs::remove(dir / "pose_2_depth.png");
  expect_error([&] { tools::calibrate_capture_directory(dir); }, ErrorCode::kNotFound,
               (dir / "pose_2_depth.png").string());
}

TEST(CalibrationCaptureFiles, PosefuseSimWritesTheCaptureOfTheSessionsRig) {
  tools::SimRunRequest request;
  request.options.duration_s = 1.0;
  request.options.color = false;
  request.options.seed = 9;
  request.options.panel_capture.enabled = true;
  request.options.panel_capture.poses = 3;
  request.out_directory = fresh_dir("session");
  const tools::SimRunResult result = tools::run_simulation(request);
  ASSERT_TRUE(result.calibration_capture.has_value());
  EXPECT_EQ(*result.calibration_capture, *request.out_directory / "calibration_capture");
  // The capture's truth is the session's rig: the header's K_from_B is the one in truth.json.
  const std::string header = session::read_file_bytes(*request.out_directory / "header.json", "header.json");
  const std::string truth = session::read_file_bytes(*result.calibration_capture / "truth.json", "truth.json");
  const auto key = header.find("\"forearm.K_from_B\"");
  ASSERT_NE(key, std::string::npos);
  const auto begin = header.find('"', header.find(':', key)) + 1;
  std::string w_x_y_z = header.substr(begin, header.find('"', begin) - begin);
  std::replace(w_x_y_z.begin(), w_x_y_z.end(), ' ', ',');
  std::string truth_K_from_B = truth.substr(truth.find("\"K_from_B\": [") + 13);
  truth_K_from_B = truth_K_from_B.substr(0, truth_K_from_B.find(']'));
  truth_K_from_B.erase(std::remove(truth_K_from_B.begin(), truth_K_from_B.end(), ' '), truth_K_from_B.end());
  EXPECT_EQ(truth_K_from_B, w_x_y_z);
  const calib::CaptureCalibration calibration = tools::calibrate_capture_directory(*result.calibration_capture);
  EXPECT_EQ(calibration.base.readings, 3);
  // A bad capture option is refused before the session is simulated.
  request.options.panel_capture.poses = 0;
  request.out_directory = fresh_dir("bad");
  expect_error([&] { tools::run_simulation(request); }, ErrorCode::kInvalidArgument, "panel_capture.poses");
}

}  // namespace
