#include "server/text_lines.hpp"

#include <sstream>

namespace posefuse::server {

std::string trim_whitespace(const std::string& text) {
  const auto first = text.find_first_not_of(" \t\r");
  if (first == std::string::npos) return {};
  const auto last = text.find_last_not_of(" \t\r");
  return text.substr(first, last - first + 1);
}

std::vector<TextLine> meaningful_lines(const std::string& file_text) {
  std::istringstream in(file_text);
  std::vector<TextLine> lines;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    std::string text = trim_whitespace(line);
    if (text.empty() || text[0] == '#') continue;
    lines.push_back({number, std::move(text)});
  }
  return lines;
}

}  // namespace posefuse::server
