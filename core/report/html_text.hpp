#pragma once
// Text for HTML: escaping and fixed-precision numbers.
#include <string>
#include <string_view>

namespace posefuse::report {

// &, <, >, " and ' as entities: safe in element text and in quoted attributes.
std::string html_escape(std::string_view text);

// `value` with `decimals` digits after the point; "-" where it is not finite.
std::string fixed(double value, int decimals);

}  // namespace posefuse::report
