#include "session/stages/imu_options.hpp"

#include "session/mag_calibration_option.hpp"
#include "session/option_reader.hpp"
#include "session/text_fields.hpp"

namespace posefuse::session {

const OptionTable& imu_option_table() {
  static const OptionTable table = [] {
    const imu::RobustOrientationFilter::Params defaults;
    return OptionTable{
        {.key = kImuTauAccKey,
         .type = OptionType::kReal,
         .default_value = format_double(defaults.tau_acc_s),
         .min = above(0),
         .unit = "s",
         .description = "inclination: time constant of the accelerometer low-pass"},
        {.key = kImuTauMagKey,
         .type = OptionType::kReal,
         .default_value = format_double(defaults.tau_mag_s),
         .min = above(0),
         .unit = "s",
         .description = "heading: time constant of the magnetometer correction"},
        {.key = kImuMagCalibrationKeys,
         .type = OptionType::kMagCalibration,
         .description =
             "magnetometer calibration made before the session (paper 1 eq. 3): the hard-iron centre (uT) and "
             "the 3x3 correction row by row; applied to the device's readings before the filter"},
    };
  }();
  return table;
}

ImuOptions read_imu_options(const v1::SessionHeader& header) {
  const OptionReader options(imu_option_table(), header);
  ImuOptions out;
  out.filter.tau_acc_s = options.real(kImuTauAccKey);
  out.filter.tau_mag_s = options.real(kImuTauMagKey);
  for (const v1::ImuDevice& device : header.imu_devices()) {
    if (auto calibration = options.mag_calibration(mag_calibration_option_key(device.device_id()))) {
      out.mag_calibrations.emplace(device.device_id(), *calibration);
    }
  }
  return out;
}

}  // namespace posefuse::session
