#include "tools/options/options_markdown.hpp"

namespace posefuse::tools {

namespace {

// A table cell: '|' would end it.
std::string cell(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (c == '|') out += '\\';
    out += c;
  }
  return out;
}

std::string code(const std::string& text) { return "`" + text + "`"; }

}  // namespace

std::string options_markdown(const std::vector<std::unique_ptr<session::Stage>>& stages) {
  std::string md;
  md += "# Session options\n\n";
  md +=
      "Generated from the stages' option tables (`core/session/stages/*_options.cpp`) by `posefuse-options-doc`; "
      "do not edit it by hand. Regenerate it from the repository root with\n\n";
  md += "    " + std::string(kRegenerateOptionsDoc) + "\n\n";
  md += "(the test `options_doc_matches_tables` fails while this file differs from the tables).\n\n";
  md +=
      "The keys the pipeline's stages read from `SessionHeader.options`, all text. `posefuse fit` and "
      "`posefuse upload` set one with `--option KEY=VALUE`; `posefuse info` lists them as the server has them. "
      "A key that is not set takes its default; a value the table does not allow ends the session with "
      "`INVALID_ARGUMENT` naming `header.options[KEY]`. A key under a stage's prefix (`imu.`, `fit.`, ...) that "
      "no stage declares, most likely a misspelt one, is ignored with an `OPTION_UNKNOWN` warning naming the "
      "nearest declared key; keys under other prefixes (`sim.seed`) are the session's own notes and pass "
      "unremarked.\n";
  for (const auto& stage : stages) {
    if (stage->options().empty()) continue;
    md += "\n## " + std::string(stage->name()) + "\n\n";
    md += std::string(stage->description()) + ".\n\n";
    md += "| Key | Default | Values | Unit | Description |\n";
    md += "|---|---|---|---|---|\n";
    for (const session::OptionSpec& option : stage->options()) {
      md += "| " + code(option.key) + " | " + (option.default_value.empty() ? "none" : code(option.default_value)) +
            " | " + cell(session::describe_values(option)) + " | " + cell(option.unit) + " | " +
            cell(option.description) + " |\n";
    }
  }
  return md;
}

}  // namespace posefuse::tools
