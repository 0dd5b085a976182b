#include "sim/mag_precalibration.hpp"

#include <cmath>
#include <vector>

#include "geometry/quaternion.hpp"
#include "sim/sim_rng.hpp"

namespace posefuse::sim {

imu::MagCalibration simulate_mag_precalibration(const ImuErrors& errors, const EarthField& field, double noise_uT,
                                                std::uint64_t seed, const std::string& stream,
                                                const MagPrecalibrationOptions& options) {
  SimRng rng(seed, stream);
  const Vec3 m_W = field.m_W_uT();
  std::vector<Vec3> readings;
  readings.reserve(static_cast<std::size_t>(options.readings));
  for (int i = 0; i < options.readings; ++i) {
    // A uniformly random orientation: a normalised 4D Gaussian.
    geometry::Quat A_from_W(rng.normal(), rng.normal(), rng.normal(), rng.normal());
    A_from_W.normalize();
    const Vec3 noise(noise_uT * rng.normal(), noise_uT * rng.normal(), noise_uT * rng.normal());
    // The sensor model of imu_synth: soft iron, hard iron, noise.
    readings.push_back(errors.soft_iron * (A_from_W * m_W) + errors.hard_iron_uT + noise);
  }
  return imu::calibrate_magnetometer(readings).calibration;
}

}  // namespace posefuse::sim
