#include "server/log.hpp"

#include <chrono>
#include <cstdio>
#include <ctime>

namespace posefuse::server {

namespace {

std::string utc_now() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()) % 1000;
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char text[64];
  std::snprintf(text, sizeof text, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday,
                tm.tm_hour, tm.tm_min, tm.tm_sec, static_cast<int>(ms.count()));
  return text;
}

// Values with spaces, quotes or '=' are quoted so that a line splits unambiguously.
void append_value(std::string& line, const std::string& value) {
  if (!value.empty() && value.find_first_of(" \"=\t\n") == std::string::npos) {
    line += value;
    return;
  }
  line += '"';
  for (const char c : value) {
    if (c == '"' || c == '\\') line += '\\';
    line += (c == '\n' || c == '\t') ? ' ' : c;
  }
  line += '"';
}

}  // namespace

void log_event(std::string_view level, std::string_view event, std::initializer_list<LogField> fields) {
  std::string line = "time=" + utc_now() + " level=" + std::string(level) + " event=" + std::string(event);
  for (const auto& [key, value] : fields) {
    line += ' ';
    line += key;
    line += '=';
    append_value(line, value);
  }
  line += '\n';
  // One stdio call per line: POSIX stdio locks the stream per call, so lines never interleave.
  std::fputs(line.c_str(), stderr);
}

}  // namespace posefuse::server
