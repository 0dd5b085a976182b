#include "report/session_report.hpp"

#include <fstream>
#include <system_error>

#include "common/error.hpp"
#include "report/html_text.hpp"
#include "report/report_sections.hpp"

namespace posefuse::report {
namespace {

const char* const kStyle = R"(
body { font-family: sans-serif; margin: 24px auto; max-width: 960px; color: #222; }
h1 { font-size: 22px; } h2 { font-size: 18px; margin-top: 28px; border-bottom: 1px solid #ccc; }
p.note, p.none { color: #555; font-size: 14px; }
table { border-collapse: collapse; font-size: 14px; margin: 8px 0; }
th, td { border: 1px solid #ccc; padding: 3px 8px; text-align: left; }
tr.partial td { color: #888; font-style: italic; }
tr.counted.uncertain td { color: #a05a00; }
svg.plot { width: 100%; height: auto; margin: 6px 0; }
svg.plot .plot-title { font-size: 14px; font-weight: bold; }
svg.plot .tick, svg.plot .legend, svg.plot .axis-label { font-size: 11px; fill: #444; }
svg.plot .grid { stroke: #e4e4e4; } svg.plot .frame { fill: none; stroke: #999; }
svg.plot .line { fill: none; stroke-width: 1.6; }
svg.plot .line.unconfident { stroke-dasharray: 3 3; opacity: 0.45; }
svg.plot .legend-line { stroke-width: 2; }
svg.plot .shade-occluded { fill: #f5c26b; opacity: 0.35; }
svg.plot .shade-recovered { fill: #8fd19e; opacity: 0.35; }
svg.plot .shade-lost { fill: #bbbbbb; opacity: 0.45; }
ul#warnings { font-size: 13px; font-family: monospace; }
)";

std::vector<std::string> read_warning_lines(const std::filesystem::path& file) {
  std::vector<std::string> lines;
  std::ifstream in(file);
  std::size_t more = 0;
  for (std::string line; std::getline(in, line);) {
    if (line.empty()) continue;
    if (lines.size() < kMaxWarningLines) {
      lines.push_back(line.size() > 2000 ? line.substr(0, 2000) + " ..." : line);
    } else {
      ++more;
    }
  }
  if (more > 0) lines.push_back("... and " + std::to_string(more) + " more lines in warnings.txt");
  return lines;
}

}  // namespace

SessionReport session_report(const session::ResultDirectory& results, const std::vector<std::string>& warning_lines,
                             const std::string& title) {
  SessionReport report;
  std::string& h = report.html;
  h = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; style-src 'unsafe-inline'\">\n"
      "<title>" +
      html_escape(title) + "</title>\n<style>" + kStyle + "</style>\n</head>\n<body>\n";
  h += "<h1>posefuse session report: " + html_escape(title) + "</h1>\n";
  const std::size_t frames = results.joint_angles.size();
  const double span_s =
      frames > 1 ? static_cast<double>(results.joint_angles.back().t_us - results.joint_angles.front().t_us) * 1e-6
                 : 0.0;
  std::size_t counted = 0;
  for (const session::RepetitionRow& r : results.repetitions) counted += r.counted ? 1 : 0;
  h += "<p id=\"overview\">" + std::to_string(frames) + " frames with joint angles over " + fixed(span_s, 1) + " s; " +
       std::to_string(counted) + " repetitions counted; " + std::to_string(warning_lines.size()) +
       " warnings and item errors.</p>\n";

  h += "<h2>Joint angles</h2>\n";
  const std::vector<PlotSpec> plots = angle_plots(results);
  if (plots.empty()) {
    h += "<p id=\"no-angles\" class=\"none\">No joint angles: they need the body fit (run with --option "
         "fit.enabled=true).</p>\n";
  } else {
    h += "<p class=\"note\">ISB angles in degrees (docs/measures.md gives each one's zero and sign). Dashed, faint "
         "lines: confidence below " +
         fixed(kConfidentAt, 1) +
         " (an assumed vertical, a held plane of elevation, a doubtful fit); gaps: no value (the geometry gives "
         "none). Shaded: the arm's IMU not seen by the camera (occluded; recovered from the IMU once the gap "
         "ended) and frames where the body fit lost tracking.</p>\n";
    for (const PlotSpec& plot : plots) h += svg_plot(plot);
  }
  report.contents.plots = plots.size();

  h += "<h2>Repetitions and range of motion</h2>\n<p class=\"note\">A repetition's confidence is the lower of its "
       "angle's confidences at its minimum and maximum; below " +
       fixed(kConfidentAt, 1) + " its range is not one to act on.</p>\n" + repetition_table(results);
  report.contents.repetitions = results.repetitions.size();
  h += "<h2>Warnings</h2>\n" + warning_list(warning_lines);
  report.contents.warnings = warning_lines.size();
  h += "<h2>Calibration</h2>\n" + calibration_table(results);
  h += "</body>\n</html>\n";
  return report;
}

ReportContents write_session_report(const std::filesystem::path& results_dir, const std::filesystem::path& out_file) {
  const session::ResultDirectory results = session::read_result_files(results_dir);
  const std::vector<std::string> warnings = read_warning_lines(results_dir / "warnings.txt");
  std::filesystem::path name = std::filesystem::absolute(results_dir).lexically_normal();
  if (name.filename().empty()) name = name.parent_path();
  const SessionReport report = session_report(results, warnings, name.filename().string());
  const std::filesystem::path partial = out_file.string() + ".partial";
  {
    std::ofstream out(partial, std::ios::binary | std::ios::trunc);
    if (!out) throw Error(ErrorCode::kNotFound, "out", "cannot write " + partial.string());
    out << report.html;
    out.close();
    if (!out) {
      std::error_code ignored;
      std::filesystem::remove(partial, ignored);
      throw Error(ErrorCode::kNotFound, "out", "writing " + partial.string() + " failed");
    }
  }
  std::filesystem::rename(partial, out_file);
  return report.contents;
}

}  // namespace posefuse::report
