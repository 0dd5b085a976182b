#pragma once
// The SessionHeader.options a stage reads, each declared once: key, type, default, range, unit and
// a one-line description. From a stage's table come the parsing and range checks
// (option_reader.hpp), the server's GetServerInfo and docs/options.md (tools/options).
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace posefuse::session {

enum class OptionType {
  kBool,            // true or false (1 or 0 too)
  kInteger,         // a whole number within [min, max]
  kReal,            // a finite number within [min, max]; or one of `words` in its place (e.g. "auto")
  kChoice,          // one of `words`
  kQuaternion,      // a unit quaternion 'w x y z' (spaces or commas)
  kMagCalibration,  // 'o_x o_y o_z' and the 3x3 correction row by row (mag_calibration_option.hpp)
};

struct OptionBound {
  double value = 0;
  bool inclusive = true;
};
inline OptionBound above(double value) { return {value, false}; }
inline OptionBound at_least(double value) { return {value, true}; }
inline OptionBound below(double value) { return {value, false}; }
inline OptionBound at_most(double value) { return {value, true}; }

// Every member has an initializer, so that a table entry names only what it sets.
struct OptionSpec {
  // e.g. "forearm.calibration_s". A key ending in a <placeholder> ("imu.mag_calibration.<device_id>")
  // stands for a family of keys: every key with the part before '<' as its prefix.
  std::string key{};
  OptionType type = OptionType::kReal;
  // As written in SessionHeader.options. Empty: no default, the option is then optional.
  std::string default_value{};
  std::optional<OptionBound> min{}, max{};  // kInteger, kReal
  std::vector<std::string> words{};         // kChoice: the values; kReal: words accepted instead of a number
  std::string unit{};                       // "s", "Hz", "deg"; empty for a count or a plain number
  std::string description{};                // one line, without the type, range and unit
};

// A stage's options, in the order GetServerInfo and docs/options.md list them.
using OptionTable = std::vector<OptionSpec>;

// "header.options[<key>]": how errors name an option.
std::string option_field(std::string_view key);

// The spec of `key` (a family member matches its family's spec); nullptr when the table has none.
const OptionSpec* find_option(const OptionTable& table, std::string_view key);

// The values an option takes, for people: "a number in (0, 120]", "'pose' or 'sdk'", "true or false".
std::string describe_values(const OptionSpec& spec);
// describe_values and the unit: "a number in (0, 120] s".
std::string describe_values_and_unit(const OptionSpec& spec);

}  // namespace posefuse::session
