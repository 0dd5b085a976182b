#pragma once
#include <Eigen/Core>

// The uncertainty of what one of RobustOrientationFilter's corrections estimates (the
// inclination or the heading) and the gain it asks for (docs/imu-robust.md, "Lost samples and
// the uncertainty").
//
// Three variances (rad^2), each updated with the gain the correction actually used (the Joseph
// form, valid for any gain):
//  - `gain_var`: what the gyro bridge and the corrections leave, from the bound a gap's rotation
//    keeps to the bridge; it sets the Kalman gain while recovering;
//  - `reported_var`: the same, but a gap adds the whole turn it may hide (the bound that needs
//    no smoothness of the motion);
//  - the evidence: the innovations measure the estimate's error too. A scalar Kalman filter on
//    that error (mean `error_mean`, variance `error_var`, prior the gap's whole turn) conditions
//    on each innovation and then moves by the correction the filter made; its mean square
//    |mean|^2 + var is what the samples show the error to be. What is reported is the smaller of
//    the two: an estimate whose samples agree with it is not left uncertain for tau_mag_s;
//  - `steady_var`: a shadow that follows the same samples with the time constant's gain from no
//    error: what steady tracking alone holds, so reported_var - steady_var is the excess.
namespace posefuse::imu {

struct CorrectionUncertainty {
  // An orientation known not at all: the inclination or the heading alone at most pi/2 RMS.
  static constexpr double kUnknownVarRad2 = 2.4674011002723395;  // (pi / 2)^2

  double gain_var_rad2 = kUnknownVarRad2;
  double reported_var_rad2 = kUnknownVarRad2;
  double steady_var_rad2 = 0.0;
  Eigen::Vector2d error_mean_rad = Eigen::Vector2d::Zero();
  double error_var_rad2 = kUnknownVarRad2;
  bool recovering = false;

  // A gap: the rotation kept to the bridge and the whole turn it may hide (rad^2), both for
  // this quantity. Starts a recovery.
  void add_gap(double bridge_var_rad2, double turn_var_rad2);

  // One correction: returns its gain, the larger of the time constant's `tau_gain`, `min_gain`
  // (what the filter takes at least: the start-up's equal-weight averaging, a fast pull after a
  // new magnetic reference) and, while recovering, a Kalman filter's for gain_var against one
  // sample's error variance. The shadow follows `tau_gain` alone: steady tracking's error, so
  // that what a start-up or a pull leaves counts as excess. The recovery ends (if
  // `may_end`) once gain_var is back within twice steady_var. `shared_var_rad2` is an error every sample shares (no
  // averaging removes it): only the uncertainty beyond it asks for a faster gain, and it stays,
  // so a later, better sample still finds the error it left.
  // `innovation_rad`: this sample's innovation (the tilt's two horizontal components, or the
  // heading and 0), from which the correction takes the returned gain's share.
  double correct(double tau_gain, double min_gain, double sample_var_rad2, double shared_var_rad2, bool may_end,
                 const Eigen::Vector2d& innovation_rad);

  // Predicted RMS error^2 beyond steady tracking.
  double excess_var_rad2() const;
};

}  // namespace posefuse::imu
