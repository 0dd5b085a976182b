#pragma once
// Magnetometer hard/soft-iron calibration of paper 1, II-E-1.
//
// The raw readings m' of a sensor rotated in all directions lie on a shifted, tilted ellipsoid
// (hard iron shifts it, soft iron stretches it). An ellipsoid fit gives its centre o, radii
// alpha, beta, gamma and axes H, and eq. 3
//   m = H diag(1/alpha, 1/beta, 1/gamma) H^T (m' - o)
// maps it onto the unit sphere. We multiply by the fitted mean field strength
//   field_strength_uT = (alpha beta gamma)^(1/3)
// (the radius of the sphere with the ellipsoid's volume) so that calibrated readings stay in uT
// with about the raw magnitude; the filter uses only their direction, other code may check
// |m| against this strength. Soft iron that shrinks or stretches the field as a whole is not
// observable from the readings, so the absolute strength is only as good as this convention.
#include <cstddef>
#include <vector>

#include "imu/ellipsoid_fit.hpp"

namespace posefuse::imu {

struct MagCalibrationParams {
  // Refuse fewer usable readings. The paper collects ~3000; 200 is the least that still gives a
  // stable fit under normal sensor noise and covers the sphere at the coverage bins below.
  std::size_t min_samples = 200;
  // Refuse if the readings, seen from the centre, hit fewer than this fraction of the direction
  // bins (direction_coverage below). Measured on synthetic readings: a sensor turned about one
  // axis hits 22%, readings from one half of the sphere 56%, 3000 readings from uniformly
  // random orientations 100%.
  double min_direction_coverage = 0.6;
  // See EllipsoidFit::condition_number.
  double max_condition_number = 100.0;
};

// The correction of eq. 3 (scaled to uT). Default-constructed: the identity (raw readings).
struct MagCalibration {
  Vec3 center_uT = Vec3::Zero();       // o, the hard-iron offset
  Vec3 radii_uT = Vec3::Ones();        // alpha, beta, gamma
  Mat3 axes = Mat3::Identity();        // H
  double field_strength_uT = 1.0;      // (alpha beta gamma)^(1/3)
  Mat3 correction = Mat3::Identity();  // field_strength_uT * H diag(1/alpha,1/beta,1/gamma) H^T

  // Eq. 3: calibrated reading in uT. A NaN (missing) reading stays NaN.
  Vec3 apply(const Vec3& raw_uT) const { return correction * (raw_uT - center_uT); }
};

struct MagCalibrationReport {
  std::size_t sample_count = 0;         // usable (finite) readings that went into the fit
  std::size_t missing_count = 0;        // readings skipped because a component was NaN (no reading)
  double relative_spread_before = 0.0;  // std/mean of |m'| (raw)
  double relative_spread_after = 0.0;   // std/mean of |m| (calibrated)
  double direction_coverage = 0.0;      // of the calibrated readings, in [0, 1]
  double condition_number = 0.0;        // of the fit (EllipsoidFit::condition_number)
};

struct MagCalibrationResult {
  MagCalibration calibration;
  MagCalibrationReport report;
};

// Fits the calibration to raw readings (uT) of a sensor rotated in all directions.
// Throws posefuse::Error kFailedPrecondition, field "mag_samples", naming the measured value and
// the limit, when there are too few usable readings, their direction coverage is too low
// (before the fit, seen from their mean, or after it), or the fit is ill-conditioned or not an
// ellipsoid; kInvalidArgument ("mag_samples[i]") on an infinite component.
MagCalibrationResult calibrate_magnetometer(const std::vector<Vec3>& raw_mag_uT,
                                            const MagCalibrationParams& params = {});

// Number of equal-area direction bins on the sphere used by direction_coverage: 8 bands equal in
// z = cos(polar angle) (equal area by Archimedes) times 16 equal longitude sectors, so each bin
// is 4 pi / 128 sr, about 18 x 22 degrees at the equator.
inline constexpr int kDirectionBins = 128;

// Fraction of the kDirectionBins bins hit by the directions of linear * (p - center).
// Points at the centre are ignored.
double direction_coverage(const std::vector<Vec3>& points, const Vec3& center, const Mat3& linear = Mat3::Identity());

}  // namespace posefuse::imu
