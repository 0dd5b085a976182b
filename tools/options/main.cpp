// posefuse-options-doc: prints docs/options.md from the stages' option tables; with --check FILE
// fails when FILE differs from what it would print.
#include <iostream>
#include <string>

#include "common/error.hpp"
#include "session/file_bytes.hpp"
#include "session/stages/default_stages.hpp"
#include "tools/options/options_markdown.hpp"

namespace {

const char* const kUsage =
    "usage: posefuse-options-doc [--check FILE]\n"
    "Prints docs/options.md (every SessionHeader.options key of the default stages: default, values,\n"
    "unit, description) from the stages' option tables. With --check FILE it prints nothing and\n"
    "exits 1 when FILE is not what it would print.\n";

// 1-based number of the first line where the two texts differ.
std::size_t first_different_line(const std::string& a, const std::string& b) {
  std::size_t line = 1;
  for (std::size_t i = 0; i < a.size() && i < b.size() && a[i] == b[i]; ++i) line += a[i] == '\n';
  return line;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace posefuse;
  const std::string args = argc > 1 ? argv[1] : "";
  if (args == "--help" || args == "-h") {
    std::cout << kUsage;
    return 0;
  }
  if (!(argc == 1 || (argc == 3 && args == "--check"))) {
    std::cerr << kUsage;
    return 2;
  }
  try {
    const std::string markdown = tools::options_markdown(session::make_default_stages());
    if (argc == 1) {
      std::cout << markdown;
      return 0;
    }
    const std::string committed = session::read_file_bytes(argv[2], argv[2]);
    if (committed == markdown) return 0;
    std::cerr << "posefuse-options-doc: " << argv[2] << " differs from the option tables (from line "
              << first_different_line(committed, markdown) << "); regenerate it from the repository root:\n  "
              << tools::kRegenerateOptionsDoc << "\n";
    return 1;
  } catch (const Error& e) {
    std::cerr << "posefuse-options-doc: " << e.field() << ": " << e.what() << '\n';
    return 1;
  }
}
