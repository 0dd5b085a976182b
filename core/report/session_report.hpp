#pragma once
// `posefuse report`: one self-contained HTML file a clinician opens (docs/report.md). Inline SVG
// and CSS only; no script, and a content security policy that lets the page load nothing.
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "session/result_reader.hpp"

namespace posefuse::report {

struct ReportContents {
  std::size_t plots = 0;
  std::size_t repetitions = 0;  // rows of the repetition table, partial ones included
  std::size_t warnings = 0;
};

struct SessionReport {
  std::string html;
  ReportContents contents;
};

SessionReport session_report(const session::ResultDirectory& results, const std::vector<std::string>& warning_lines,
                             const std::string& title);

// At most this many lines of warnings.txt are listed; the rest are counted in a last line.
inline constexpr std::size_t kMaxWarningLines = 500;

// Reads results_dir (session::read_result_files and the client's warnings.txt) and writes
// out_file through a temporary file beside it. Throws posefuse::Error: the reader's, and
// kNotFound "out" when the file cannot be written.
ReportContents write_session_report(const std::filesystem::path& results_dir, const std::filesystem::path& out_file);

}  // namespace posefuse::report
