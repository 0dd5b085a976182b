#include "session/option_reader.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "common/error.hpp"
#include "session/mag_calibration_option.hpp"
#include "session/text_fields.hpp"

namespace posefuse::session {

namespace {

bool in_range(const OptionSpec& spec, double value) {
  if (spec.min && !(spec.min->inclusive ? value >= spec.min->value : value > spec.min->value)) return false;
  if (spec.max && !(spec.max->inclusive ? value <= spec.max->value : value < spec.max->value)) return false;
  return true;
}

// "is '121', must be a number in (0, 120] s".
[[noreturn]] void throw_not_allowed(const OptionSpec& spec, std::string_view key, const std::string& text) {
  throw_invalid(option_field(key), "is " + session::quoted(text) + ", must be " + describe_values_and_unit(spec));
}

bool is_word(const OptionSpec& spec, const std::string& text) {
  return std::find(spec.words.begin(), spec.words.end(), text) != spec.words.end();
}

const char* type_name(OptionType type) {
  switch (type) {
    case OptionType::kBool: return "bool";
    case OptionType::kInteger: return "integer";
    case OptionType::kReal: return "real";
    case OptionType::kChoice: return "choice";
    case OptionType::kQuaternion: return "quaternion";
    case OptionType::kMagCalibration: return "mag calibration";
  }
  return "?";
}

}  // namespace

OptionReader::OptionReader(const OptionTable& table, const v1::SessionHeader& header)
    : table_(table), header_(header) {}

const OptionSpec& OptionReader::spec(std::string_view key, OptionType type) const {
  const OptionSpec* found = find_option(table_, key);
  if (!found) throw Error(ErrorCode::kInternal, option_field(key), "is not in the stage's option table");
  if (found->type != type) {
    throw Error(ErrorCode::kInternal, option_field(key),
                std::string("is a ") + type_name(found->type) + " option, read as a " + type_name(type));
  }
  return *found;
}

bool OptionReader::given(std::string_view key) const {
  if (!find_option(table_, key))
    throw Error(ErrorCode::kInternal, option_field(key), "is not in the stage's option table");
  return header_.options().find(std::string(key)) != header_.options().end();
}

std::optional<std::string> OptionReader::text(const OptionSpec& spec, std::string_view key) const {
  const auto it = header_.options().find(std::string(key));
  if (it != header_.options().end()) return it->second;
  if (spec.default_value.empty()) return std::nullopt;
  return spec.default_value;
}

std::string OptionReader::required_text(const OptionSpec& spec, std::string_view key) const {
  std::optional<std::string> value = text(spec, key);
  if (!value) throw Error(ErrorCode::kInternal, option_field(key), "has no default; read it as optional");
  return *value;
}

bool OptionReader::boolean(std::string_view key) const {
  const OptionSpec& s = spec(key, OptionType::kBool);
  const std::string value = required_text(s, key);
  if (value == "true" || value == "1") return true;
  if (value == "false" || value == "0") return false;
  throw_not_allowed(s, key, value);
}

std::int64_t OptionReader::integer(std::string_view key) const {
  const std::optional<std::int64_t> value = optional_integer(key);
  if (!value) throw Error(ErrorCode::kInternal, option_field(key), "has no default; read it as optional");
  return *value;
}

std::optional<std::int64_t> OptionReader::optional_integer(std::string_view key) const {
  const OptionSpec& s = spec(key, OptionType::kInteger);
  const std::optional<std::string> value = text(s, key);
  if (!value) return std::nullopt;
  std::int64_t number = 0;
  try {
    number = parse_int64(*value, option_field(key));
  } catch (const Error&) {
    throw_not_allowed(s, key, *value);
  }
  if (!in_range(s, static_cast<double>(number))) throw_not_allowed(s, key, *value);
  return number;
}

double OptionReader::real(std::string_view key) const {
  const OptionSpec& s = spec(key, OptionType::kReal);
  const std::string value = required_text(s, key);
  if (is_word(s, value)) throw Error(ErrorCode::kInternal, option_field(key), "holds a word; ask word() first");
  double number = 0;
  try {
    number = parse_double(value, option_field(key));
  } catch (const Error&) {
    throw_not_allowed(s, key, value);
  }
  if (!std::isfinite(number) || !in_range(s, number)) throw_not_allowed(s, key, value);
  return number;
}

std::optional<std::string> OptionReader::word(std::string_view key) const {
  const OptionSpec& s = spec(key, OptionType::kReal);
  const std::string value = required_text(s, key);
  if (is_word(s, value)) return value;
  return std::nullopt;
}

bool OptionReader::choice_is(std::string_view key, std::string_view value) const {
  const OptionSpec& s = spec(key, OptionType::kChoice);
  if (!is_word(s, std::string(value))) {
    throw Error(ErrorCode::kInternal, option_field(key), session::quoted(value) + " is not one of its choices");
  }
  const std::string chosen = required_text(s, key);
  if (!is_word(s, chosen)) throw_not_allowed(s, key, chosen);
  return chosen == value;
}

std::optional<Eigen::Quaterniond> OptionReader::quaternion(std::string_view key) const {
  const OptionSpec& s = spec(key, OptionType::kQuaternion);
  const std::optional<std::string> value = text(s, key);
  if (!value) return std::nullopt;
  const std::string field = option_field(key);
  std::string spaced = *value;
  std::replace(spaced.begin(), spaced.end(), ',', ' ');
  std::istringstream words(spaced);
  std::vector<double> numbers;
  try {
    for (std::string word; words >> word;) numbers.push_back(parse_double(word, field));
  } catch (const Error&) {
    numbers.clear();
  }
  if (numbers.size() != 4) throw_invalid(field, "is " + session::quoted(*value) + ", expected four numbers 'w x y z'");
  const Eigen::Quaterniond q(numbers[0], numbers[1], numbers[2], numbers[3]);
  if (!q.coeffs().allFinite() || std::abs(q.norm() - 1.0) > 1e-3) {
    throw_invalid(field, "is " + session::quoted(*value) + ", not a unit quaternion");
  }
  return q.normalized();
}

std::optional<imu::MagCalibration> OptionReader::mag_calibration(std::string_view key) const {
  const OptionSpec& s = spec(key, OptionType::kMagCalibration);
  const std::optional<std::string> value = text(s, key);
  if (!value) return std::nullopt;
  return parse_mag_calibration(*value, option_field(key));
}

}  // namespace posefuse::session
