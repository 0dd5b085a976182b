#include "imu/correction_uncertainty.hpp"

#include <algorithm>

namespace posefuse::imu {

namespace {

// The Joseph form for gain k with the part of var beyond `shared` reduced and the shared part kept.
double after_correction(double var, double k, double sample_var, double shared) {
  const double excess = std::max(0.0, var - shared);
  return (var - excess) + (1.0 - k) * (1.0 - k) * excess + k * k * sample_var;
}

}  // namespace

void CorrectionUncertainty::add_gap(double bridge_var_rad2, double turn_var_rad2) {
  gain_var_rad2 = std::min(kUnknownVarRad2, gain_var_rad2 + bridge_var_rad2);
  reported_var_rad2 = std::min(kUnknownVarRad2, reported_var_rad2 + turn_var_rad2);
  error_var_rad2 = std::min(kUnknownVarRad2, error_var_rad2 + turn_var_rad2);
  recovering = true;
}

double CorrectionUncertainty::excess_var_rad2() const {
  const double evidence = error_mean_rad.squaredNorm() + error_var_rad2;
  return std::max(0.0, std::min(reported_var_rad2, evidence) - steady_var_rad2);
}

double CorrectionUncertainty::correct(double tau_gain, double min_gain, double sample_var_rad2, double shared_var_rad2,
                                      bool may_end, const Eigen::Vector2d& innovation_rad) {
  steady_var_rad2 = after_correction(steady_var_rad2, tau_gain, sample_var_rad2, shared_var_rad2);
  double k = std::max(tau_gain, min_gain);
  if (recovering) {
    const double excess = std::max(0.0, gain_var_rad2 - shared_var_rad2);
    k = std::max(k, excess / (excess + sample_var_rad2));
  }
  gain_var_rad2 = after_correction(gain_var_rad2, k, sample_var_rad2, shared_var_rad2);
  reported_var_rad2 = after_correction(reported_var_rad2, k, sample_var_rad2, shared_var_rad2);
  // The evidence: the innovation is the error plus one sample's; condition on it (the shared
  // part cannot be told from the samples and stays), then follow the correction.
  const double error_excess = std::max(0.0, error_var_rad2 - shared_var_rad2);
  const double evidence_gain = error_excess / (error_excess + sample_var_rad2);
  error_mean_rad += evidence_gain * (innovation_rad - error_mean_rad);
  // Never below steady tracking's own: the error keeps moving, so the samples keep being heard.
  error_var_rad2 = std::max(error_var_rad2 - evidence_gain * error_excess, steady_var_rad2);
  error_mean_rad -= k * innovation_rad;
  // The recovery ends when what the gap left is no more than steady tracking's own error; not
  // merely because the samples say little for now (an arm still swinging).
  if (recovering && may_end && gain_var_rad2 <= shared_var_rad2 + 2.0 * steady_var_rad2) recovering = false;
  return k;
}

}  // namespace posefuse::imu
