#pragma once
// Structured one-line logs to stderr: `time=... level=info event=session_end session=3 ...`.
// Only operational facts go here (ids, counts, codes, durations, peer addresses); never patient
// data: no subject ids, header contents or error messages that could quote input values.
#include <initializer_list>
#include <string>
#include <string_view>
#include <utility>

namespace posefuse::server {

using LogField = std::pair<std::string_view, std::string>;

void log_event(std::string_view level, std::string_view event, std::initializer_list<LogField> fields = {});

}  // namespace posefuse::server
