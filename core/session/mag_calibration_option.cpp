#include "session/mag_calibration_option.hpp"

#include <cmath>
#include <sstream>
#include <vector>

#include "common/error.hpp"
#include "session/stages/imu_options.hpp"
#include "session/text_fields.hpp"

namespace posefuse::session {

std::string mag_calibration_option_key(const std::string& device_id) {
  const std::string family = kImuMagCalibrationKeys;
  return family.substr(0, family.find('<')) + device_id;
}

std::string format_mag_calibration(const imu::MagCalibration& calibration) {
  std::string text;
  for (int i = 0; i < 3; ++i) text += (i ? " " : "") + format_double(calibration.center_uT[i]);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) text += " " + format_double(calibration.correction(r, c));
  }
  return text;
}

imu::MagCalibration parse_mag_calibration(const std::string& text, const std::string& field) {
  std::istringstream words(text);
  std::vector<double> values;
  for (std::string word; words >> word;) values.push_back(parse_double(word, field));
  if (values.size() != 12) {
    throw_invalid(field, "is " + session::quoted(text) +
                             ", expected 12 numbers: the centre o_x o_y o_z (uT) and the 3x3 "
                             "correction row by row");
  }
  imu::MagCalibration calibration;
  for (const double v : values) {
    if (!std::isfinite(v)) throw_invalid(field, "is " + session::quoted(text) + ", not all finite");
  }
  calibration.center_uT = imu::Vec3(values[0], values[1], values[2]);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) calibration.correction(r, c) = values[static_cast<std::size_t>(3 + 3 * r + c)];
  }
  const double det = calibration.correction.determinant();
  if (!(std::abs(det) > 1e-9 * std::pow(calibration.correction.norm(), 3))) {
    throw_invalid(field, "is " + session::quoted(text) + ": the correction matrix is singular");
  }
  return calibration;
}

}  // namespace posefuse::session
