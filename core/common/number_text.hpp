#pragma once
// A number in an error or warning message, with the decimals its unit needs ("7.0 cm").
#include <charconv>
#include <string>

namespace posefuse {

inline std::string fixed_text(double value, int decimals) {
  char buffer[64];
  const auto [end, error] = std::to_chars(buffer, buffer + sizeof buffer, value, std::chars_format::fixed, decimals);
  return error == std::errc{} ? std::string(buffer, end) : std::string("(out of range)");
}

}  // namespace posefuse
