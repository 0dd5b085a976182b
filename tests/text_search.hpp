#pragma once
// Small text helpers for tests that check files and markup they wrote.
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace posefuse::testing {

// The whole file as text ("" when it cannot be read).
inline std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Non-overlapping occurrences of `part` in `text`.
inline std::size_t count_occurrences(const std::string& text, const std::string& part) {
  std::size_t n = 0;
  for (auto at = text.find(part); at != std::string::npos; at = text.find(part, at + part.size())) ++n;
  return n;
}

}  // namespace posefuse::testing
