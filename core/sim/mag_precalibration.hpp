#pragma once
// The magnetometer calibration of paper 1, II-E-1, as a clinic does it before the session: the
// IMU turned by hand in all directions until ~3000 readings are collected, an ellipsoid fit
// (imu::calibrate_magnetometer, eq. 3). Simulated with the device's own static errors (hard and
// soft iron) and magnetometer noise, in the undisturbed earth field, so the result carries the
// fit's real error, not the truth. The session header passes it to the IMU stage
// (session/mag_calibration_option.hpp).
#include <cstdint>
#include <string>

#include "imu/mag_calibration.hpp"
#include "sim/imu_synth.hpp"

namespace posefuse::sim {

struct MagPrecalibrationOptions {
  int readings = 3000;  // the paper's count
};

// `stream` seeds the random orientations and noise (SimRng(seed, stream)). posefuse::Error from
// the fit when it fails (e.g. noise far above the field).
imu::MagCalibration simulate_mag_precalibration(const ImuErrors& errors, const EarthField& field, double noise_uT,
                                                std::uint64_t seed, const std::string& stream,
                                                const MagPrecalibrationOptions& options = {});

}  // namespace posefuse::sim
