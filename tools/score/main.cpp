// posefuse-score: scores a result directory against ground truth of the same layout (the
// client's results against the simulator's gt/; eval/result_score.hpp says what is compared).
#include <iostream>
#include <string>

#include "common/error.hpp"
#include "eval/result_score.hpp"
#include "session/text_fields.hpp"

namespace {

const char* const kUsage =
    "usage: posefuse-score RESULT_DIR GT_DIR [--tolerance-us N]\n"
    "Prints per stream the error of RESULT_DIR against GT_DIR (both in the result-file layout of\n"
    "`posefuse fit`, docs/simulator.md \"Ground truth: gt/\"): forearm orientation (paper 1\n"
    "eqs. 14-15), IMU position, joint groups, calibration values. Rows are matched to the truth by\n"
    "nearest t_us within the tolerance (default 2000 us).\n";

int fail(const std::string& message) {
  std::cerr << "posefuse-score: " << message << '\n';
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace posefuse;
  try {
    std::vector<std::string> directories;
    eval::ScoreOptions options;
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if (arg == "--help" || arg == "-h") {
        std::cout << kUsage;
        return 0;
      }
      if (arg == "--tolerance-us") {
        if (i + 1 >= argc) return fail("--tolerance-us: needs a value");
        options.tolerance_us = session::parse_int64(argv[++i], "--tolerance-us");
        if (options.tolerance_us < 0) return fail("--tolerance-us: must not be negative");
      } else if (!arg.empty() && arg[0] == '-') {
        return fail("unknown flag '" + arg + "'\n" + kUsage);
      } else {
        directories.push_back(arg);
      }
    }
    if (directories.size() != 2) return fail(std::string("expected RESULT_DIR and GT_DIR\n") + kUsage);
    const eval::ScoreReport report = eval::score_directories(directories[0], directories[1], options);
    std::cout << "posefuse-score " << directories[0] << " against " << directories[1] << "\n\n"
              << eval::format_score_report(report);
    return 0;
  } catch (const posefuse::Error& e) {
    return fail(e.what());  // names the field
  } catch (const std::exception& e) {
    return fail(e.what());
  }
}
