#include "session/option_table.hpp"

#include "session/text_fields.hpp"

namespace posefuse::session {

namespace {

// "in (0, 120]", "> 0", "<= 1"; empty without bounds.
std::string range_text(const OptionSpec& spec) {
  if (spec.min && spec.max) {
    return "in " + std::string(spec.min->inclusive ? "[" : "(") + format_double(spec.min->value) + ", " +
           format_double(spec.max->value) + (spec.max->inclusive ? "]" : ")");
  }
  if (spec.min) return std::string(spec.min->inclusive ? ">= " : "> ") + format_double(spec.min->value);
  if (spec.max) return std::string(spec.max->inclusive ? "<= " : "< ") + format_double(spec.max->value);
  return "";
}

// "'a'", "'a' or 'b'", "'a', 'b' or 'c'".
std::string word_list(const std::vector<std::string>& words) {
  std::string text;
  for (std::size_t i = 0; i < words.size(); ++i) {
    if (i > 0) text += i + 1 == words.size() ? " or " : ", ";
    text += session::quoted(words[i]);
  }
  return text;
}

std::string with_range(std::string what, const OptionSpec& spec) {
  const std::string range = range_text(spec);
  return range.empty() ? what : what + " " + range;
}

// describe_values, with the unit after the numbers when `with_unit`.
std::string describe(const OptionSpec& spec, bool with_unit) {
  const std::string unit = with_unit && !spec.unit.empty() ? " " + spec.unit : "";
  switch (spec.type) {
    case OptionType::kBool: return "true or false";
    case OptionType::kInteger: return with_range("an integer", spec) + unit;
    case OptionType::kReal: {
      std::string text = with_range("a number", spec) + unit;
      if (!spec.words.empty()) text += " or " + word_list(spec.words);
      return text;
    }
    case OptionType::kChoice: return word_list(spec.words);
    case OptionType::kQuaternion: return "a unit quaternion 'w x y z'";
    case OptionType::kMagCalibration: return "12 numbers 'o_x o_y o_z c00 c01 c02 c10 c11 c12 c20 c21 c22'" + unit;
  }
  return "";
}

}  // namespace

std::string option_field(std::string_view key) { return "header.options[" + std::string(key) + "]"; }

const OptionSpec* find_option(const OptionTable& table, std::string_view key) {
  for (const OptionSpec& spec : table) {
    if (spec.key == key) return &spec;
    const std::size_t placeholder = spec.key.find('<');
    if (placeholder != std::string::npos && key.size() > placeholder &&
        key.substr(0, placeholder) == std::string_view(spec.key).substr(0, placeholder)) {
      return &spec;
    }
  }
  return nullptr;
}

std::string describe_values(const OptionSpec& spec) { return describe(spec, false); }

std::string describe_values_and_unit(const OptionSpec& spec) { return describe(spec, true); }

}  // namespace posefuse::session
