#pragma once
// A stage's SessionHeader.options read against its table (option_table.hpp): the header's text
// or the table's default, parsed as the spec's type and checked against its range.
//
// A bad value throws posefuse::Error (kInvalidArgument) naming the option,
// "header.options[forearm.calibration_s]", with the value and what it must be. Asking for a key
// the table lacks, or as another type than the table's, is a bug of ours (kInternal).
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include <Eigen/Geometry>

#include "imu/mag_calibration.hpp"
#include "posefuse/v1/session.pb.h"
#include "session/option_table.hpp"

namespace posefuse::session {

class OptionReader {
 public:
  // Both must outlive the reader.
  OptionReader(const OptionTable& table, const v1::SessionHeader& header);

  // Whether the header sets `key` (a default does not count).
  bool given(std::string_view key) const;

  bool boolean(std::string_view key) const;
  std::int64_t integer(std::string_view key) const;
  // None when the header does not set it and the table has no default.
  std::optional<std::int64_t> optional_integer(std::string_view key) const;
  // A kReal that is not one of its words.
  double real(std::string_view key) const;
  // The word a kReal holds instead of a number; none when it holds a number.
  std::optional<std::string> word(std::string_view key) const;
  // Whether a kChoice holds `value` (which must be one of its words).
  bool choice_is(std::string_view key, std::string_view value) const;
  // Normalised; none when not set and without default.
  std::optional<Eigen::Quaterniond> quaternion(std::string_view key) const;
  // `key` a member of a kMagCalibration family ("imu.mag_calibration.left"); none when not set.
  std::optional<imu::MagCalibration> mag_calibration(std::string_view key) const;

 private:
  const OptionSpec& spec(std::string_view key, OptionType type) const;
  // The header's text, else the default; none when neither.
  std::optional<std::string> text(const OptionSpec& spec, std::string_view key) const;
  std::string required_text(const OptionSpec& spec, std::string_view key) const;

  const OptionTable& table_;
  const v1::SessionHeader& header_;
};

}  // namespace posefuse::session
