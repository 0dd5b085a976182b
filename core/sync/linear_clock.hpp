#pragma once
// A device clock mapped linearly onto a reference clock, and its robust fit from observations.
//
// Paper 1 (II-G) assumes a constant offset per device. Crystal clocks drift by tens of ppm, i.e.
// tens of milliseconds over a ten-minute session, more than a depth frame at the end of it, so
// we fit offset + drift and carry the covariance so every mapped time has an uncertainty.
#include <vector>

#include <Eigen/Core>

#include "sync/buzzer_stop.hpp"

namespace posefuse::sync {

// reference_us = device_us + offset_us + drift * (device_us - anchor_device_us)
struct LinearClock {
  double anchor_device_us = 0.0;
  double offset_us = 0.0;                                // reference - device at the anchor
  double drift = 0.0;                                    // dimensionless rate error, 1e-6 = 1 ppm
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();  // of (offset_us, drift)

  double to_reference_us(double device_us) const;
  double sigma_us(double device_us) const;  // 1-sigma of to_reference_us
};

// The map device -> outer reference through an intermediate clock:
// outer_from_mid(mid_from_device(t)). Independent errors; the covariance is propagated exactly
// for the composed line (first order in the drifts' product).
LinearClock compose(const LinearClock& outer_from_mid, const LinearClock& mid_from_device);

struct ClockFitOptions {
  double drift_prior_sigma = 100e-6;  // zero-mean prior on the drift; lets one event give an
                                      // offset whose uncertainty grows away from it
  double outlier_sigmas = 4.0;        // reject |residual| > this many (robust) sigmas
  double min_sigma_us = 1.0;          // floor on each observation's sigma
  int max_iterations = 20;
};

struct ClockFit {
  LinearClock clock;
  std::vector<bool> inlier;  // per observation
  int inlier_count = 0;
  double residual_rms_us = 0.0;  // over inliers
};

// Robust weighted least squares of reference - device = offset + drift * (device - anchor),
// anchor = mean device time. Starts from a pairwise-slope median (robust to a large share of
// outliers), then alternates weighted least squares on inliers with rejection at
// `outlier_sigmas` times the robust spread of the normalised residuals (never tighter than the
// observations' own sigmas). The covariance is inflated when the inliers scatter more than their
// sigmas claim. Throws posefuse::Error: kInvalidArgument "observations[i].*" on non-finite or
// negative values, "observations" when empty.
ClockFit fit_linear_clock(const std::vector<ClockObservation>& observations, const ClockFitOptions& options = {});

}  // namespace posefuse::sync
