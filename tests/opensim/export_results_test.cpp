// `posefuse export` on a result directory written by session::ResultFiles: each format lands
// under its default name, a failed export leaves no file, and errors name what is missing.
#include <gtest/gtest.h>

#include <string>

#include "../eval/result_fixture.hpp"
#include "../imu/expect_error.hpp"
#include "../text_search.hpp"
#include "opensim/export_results.hpp"

using namespace posefuse;
using posefuse::testing::read_text;

TEST(ExportResults, WritesEachFormatUnderItsDefaultName) {
  const auto dir = result_fixture::fresh_result_dir("export_all");
  result_fixture::FixtureSpec spec;
  spec.level_camera = true;
  result_fixture::write_fixture(dir, spec);
  for (const char* name : {"trc", "mot", "sto"}) {
    const auto format = opensim::export_format(name);
    ASSERT_TRUE(format.has_value()) << name;
    const opensim::ExportReport report = opensim::export_results(dir, *format);
    EXPECT_EQ(report.file, dir / opensim::default_export_name(*format));
    EXPECT_TRUE(std::filesystem::exists(report.file)) << report.file;
    EXPECT_FALSE(std::filesystem::exists(report.file.string() + ".partial"));
    EXPECT_FALSE(report.summary.empty());
  }
  // The fixture's camera skeleton: 10 frames of the 25 Kinect joints.
  const std::string trc = read_text(dir / "markers.trc");
  EXPECT_NE(trc.find("\t10\t25\tm\t"), std::string::npos) << trc.substr(0, 300);
  const std::string mot = read_text(dir / "joint_angles.mot");
  EXPECT_NE(mot.find("nRows=10\n"), std::string::npos);
  EXPECT_NE(mot.find("inDegrees=yes\n"), std::string::npos);
  const std::string sto = read_text(dir / "imu_orientations.sto");
  EXPECT_NE(sto.find("ground=camera\nclock=camera\n"), std::string::npos);
  EXPECT_NE(sto.find("time\tradius_r_imu\n"), std::string::npos);
}

TEST(ExportResults, ReportsTheHeldAnglesAsNaNInAWarning) {
  const auto dir = result_fixture::fresh_result_dir("export_warning");
  result_fixture::FixtureSpec spec;
  spec.level_camera = true;
  result_fixture::write_fixture(dir, spec);
  const opensim::ExportReport report = opensim::export_results(dir, opensim::ExportFormat::kMot, dir / "angles.mot");
  EXPECT_EQ(report.file, dir / "angles.mot");
  ASSERT_EQ(report.warnings.size(), 1u);
  EXPECT_NE(report.warnings[0].find("10 angle values are NaN"), std::string::npos) << report.warnings[0];
}

TEST(ExportResults, RefusesACameraWhoseVerticalIsItsAxis) {
  const auto dir = result_fixture::fresh_result_dir("export_vertical_axis");
  result_fixture::write_fixture(dir, result_fixture::FixtureSpec{});  // K_from_W about z: up is K's z
  posefuse::testing::expect_error([&] { opensim::export_results(dir, opensim::ExportFormat::kTrc); },
                                  ErrorCode::kFailedPrecondition, "calibration.json", "no horizontal front");
  EXPECT_FALSE(std::filesystem::exists(dir / "markers.trc"));
}

TEST(ExportResults, AFailedExportLeavesNoFile) {
  const auto dir = result_fixture::fresh_result_dir("export_fails");
  std::filesystem::create_directories(dir);
  posefuse::testing::expect_error([&] { opensim::export_results(dir, opensim::ExportFormat::kMot); },
                                  ErrorCode::kFailedPrecondition, "joint_angles.csv");
  EXPECT_TRUE(std::filesystem::is_empty(dir));
  posefuse::testing::expect_error([&] { opensim::export_results(dir / "missing", opensim::ExportFormat::kTrc); },
                                  ErrorCode::kNotFound, (dir / "missing").string());
  posefuse::testing::expect_error(
      [&] { opensim::export_results(dir, opensim::ExportFormat::kSto, dir / "no_such_folder" / "x.sto"); },
      ErrorCode::kNotFound, "out", "cannot write");
  posefuse::testing::expect_error([&] { opensim::export_results(dir, opensim::ExportFormat::kSto); },
                                  ErrorCode::kFailedPrecondition, "imu_orientations");
  EXPECT_TRUE(std::filesystem::is_empty(dir));
}
