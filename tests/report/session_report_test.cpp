// The session report from a result directory written by session::ResultFiles: its sections,
// what it says when results are missing, and that nothing in it loads or runs anything.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "../eval/result_fixture.hpp"
#include "../imu/expect_error.hpp"
#include "../text_search.hpp"
#include "report/session_report.hpp"

using namespace posefuse;
using posefuse::testing::count_occurrences;
using posefuse::testing::read_text;

namespace {}  // namespace

TEST(SessionReport, HoldsThePlotsTablesWarningsAndCalibration) {
  const auto dir = result_fixture::fresh_result_dir("report_all");
  result_fixture::FixtureSpec spec;
  spec.frames = 60;
  result_fixture::write_fixture(dir, spec);
  std::ofstream(dir / "warnings.txt") << "warning [A] f: first\n\nwarning [B] g: <img src=x onerror=alert(1)>\n";
  const report::ReportContents contents = report::write_session_report(dir, dir / "report.html");
  EXPECT_EQ(contents.plots, 5u);
  EXPECT_EQ(contents.repetitions, 3u);
  EXPECT_EQ(contents.warnings, 2u);
  const std::string html = read_text(dir / "report.html");
  EXPECT_EQ(count_occurrences(html, "<svg class=\"plot\""), 5u);
  EXPECT_NE(html.find("<table id=\"repetitions\">"), std::string::npos);
  EXPECT_EQ(count_occurrences(html, "<tr class=\"counted\">"), 1u);
  // The second counted repetition's range is at confidence 0.3: marked, still counted.
  EXPECT_EQ(count_occurrences(html, "<tr class=\"counted uncertain\">"), 1u);
  EXPECT_NE(html.find("<td>0.30</td><td>range not confident</td>"), std::string::npos);
  // Cut at a turn near the middle of the range, the row says so and by how much.
  spec.uncertain_cut_ambiguity_deg = 40;
  result_fixture::write_fixture(dir, spec);
  report::write_session_report(dir, dir / "report.html");
  EXPECT_NE(read_text(dir / "report.html")
                .find("<td>0.30</td><td>range not confident: cut at a turn near the middle of the range, up to 40 "
                      "deg</td>"),
            std::string::npos);
  EXPECT_EQ(count_occurrences(html, "<tr class=\"partial\">"), 1u);
  EXPECT_NE(html.find("<table id=\"repetition-summary\">"), std::string::npos);
  EXPECT_NE(html.find("<td>right_elbow_flexion</td><td>2</td><td>45.0</td><td>7.1</td>"), std::string::npos);
  EXPECT_NE(html.find("<table id=\"calibration\">"), std::string::npos);
  EXPECT_NE(html.find("right forearm (imu_right)"), std::string::npos);
  EXPECT_NE(html.find("&lt;img src=x onerror=alert(1)&gt;"), std::string::npos);
  // The held left plane of elevation (confidence 0) is drawn faint; the right arm's IMU is
  // PREDICTED for the second half of the frames: one occluded stretch per right-arm plot.
  EXPECT_NE(html.find("line unconfident"), std::string::npos);
  EXPECT_EQ(count_occurrences(html, "<rect class=\"shade shade-occluded\""), 2u * 2u);  // stretch + legend, 2 plots
  EXPECT_EQ(count_occurrences(html, "<script"), 0u);
  EXPECT_EQ(count_occurrences(html, "<img"), 0u);
}

TEST(SessionReport, SaysWhatIsMissing) {
  const auto dir = result_fixture::fresh_result_dir("report_empty");
  std::filesystem::create_directories(dir);
  const report::ReportContents contents = report::write_session_report(dir, dir / "r.html");
  EXPECT_EQ(contents.plots, 0u);
  const std::string html = read_text(dir / "r.html");
  EXPECT_NE(html.find("No joint angles: they need the body fit"), std::string::npos);
  EXPECT_NE(html.find("No repetitions were found"), std::string::npos);
  EXPECT_NE(html.find("No warnings."), std::string::npos);
  EXPECT_NE(html.find("No calibration report"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir / "r.html.partial"));
}

TEST(SessionReport, NamesAMissingDirectoryAndAnUnwritableFile) {
  const auto dir = result_fixture::fresh_result_dir("report_errors");
  std::filesystem::create_directories(dir);
  posefuse::testing::expect_error([&] { report::write_session_report(dir / "none", dir / "r.html"); },
                                  ErrorCode::kNotFound, (dir / "none").string());
  posefuse::testing::expect_error([&] { report::write_session_report(dir, dir / "no" / "r.html"); },
                                  ErrorCode::kNotFound, "out", "cannot write");
}

TEST(SessionReport, ListsAtMostTheFirstWarningsAndCountsTheRest) {
  const auto dir = result_fixture::fresh_result_dir("report_many_warnings");
  std::filesystem::create_directories(dir);
  {
    std::ofstream out(dir / "warnings.txt");
    for (std::size_t i = 0; i < report::kMaxWarningLines + 7; ++i) out << "warning [W] f: " << i << "\n";
  }
  const report::ReportContents contents = report::write_session_report(dir, dir / "r.html");
  EXPECT_EQ(contents.warnings, report::kMaxWarningLines + 1);
  EXPECT_NE(read_text(dir / "r.html").find("... and 7 more lines in warnings.txt"), std::string::npos);
}
