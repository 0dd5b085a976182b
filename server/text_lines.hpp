#pragma once
// The lines of the server's small text files (tokens file, config file) that hold something:
// surrounding whitespace trimmed, blank lines and lines starting with '#' left out, each with
// its 1-based line number for error messages.
#include <string>
#include <vector>

namespace posefuse::server {

struct TextLine {
  int number = 0;
  std::string text;
};

std::vector<TextLine> meaningful_lines(const std::string& file_text);

// `text` without leading and trailing spaces, tabs and carriage returns.
std::string trim_whitespace(const std::string& text);

}  // namespace posefuse::server
