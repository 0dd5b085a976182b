#pragma once
// The body-fit stage's SessionHeader.options: their table and what they hold.
#include <cstdint>
#include <optional>

#include "fit/fit_options.hpp"
#include "fit/pose_smoothing.hpp"
#include "fit/start_extrapolation.hpp"
#include "posefuse/v1/session.pb.h"
#include "session/option_table.hpp"

namespace posefuse::session {

inline constexpr const char* kFitEnabledKey = "fit.enabled";
inline constexpr const char* kFitCalibrationSKey = "fit.calibration_s";
inline constexpr const char* kFitBodyIdKey = "fit.body_id";
inline constexpr const char* kFitSmoothingFramesKey = "fit.smoothing_frames";
inline constexpr const char* kFitImuWaitSKey = "fit.imu_wait_s";
inline constexpr const char* kFitLostEnergyKey = "fit.lost_energy";
inline constexpr const char* kFitTrustedEnergyKey = "fit.trusted_energy";
inline constexpr const char* kFitMaxIterationsKey = "fit.max_iterations";
inline constexpr const char* kFitFineShapeKey = "fit.fine_shape";
inline constexpr const char* kFitLambdaImuKey = "fit.lambda_imu";
inline constexpr const char* kFitSkeletonStartEnergyKey = "fit.skeleton_start_energy";
inline constexpr const char* kFitFreezeContourAfterKey = "fit.freeze_contour_after";
inline constexpr const char* kFitMinJointStepMKey = "fit.min_joint_step_m";
inline constexpr const char* kFitJointStepStopMaxDampingKey = "fit.joint_step_stop_max_damping";
inline constexpr const char* kFitProjectStepsOntoLimitsKey = "fit.project_steps_onto_limits";
inline constexpr const char* kFitLineariseDistancesKey = "fit.linearise_distances";
inline constexpr const char* kFitSilhouetteEdgePxKey = "fit.silhouette_edge_px";
inline constexpr const char* kFitStartVelocityGainKey = "fit.start_velocity_gain";

// What the options say, as the stage uses it. The defaults are the table's (read_body_fit_options).
struct BodyFitOptions {
  double calibration_s = 0;              // fit.calibration_s
  std::optional<std::uint32_t> body_id;  // fit.body_id; none: the first skeleton's
  fit::PoseSmoothingOptions smoothing;   // window_frames: fit.smoothing_frames
  double imu_wait_s = 0;                 // fit.imu_wait_s
  double lost_energy = 0;                // fit.lost_energy
  double trusted_energy = 0;             // fit.trusted_energy
  bool fine_shape = false;               // fit.fine_shape
  double skeleton_start_energy = 0;      // fit.skeleton_start_energy
  // max_iterations, lambda_imu, freeze_contour_after, min_joint_step_m, joint_step_stop_max_damping,
  // project_steps_onto_limits, linearise_distances and silhouette_edge_px from the options, the rest
  // fit::FitOptions' own defaults.
  fit::FitOptions fit;
  fit::StartExtrapolationOptions extrapolation;  // velocity_gain: fit.start_velocity_gain
};

const OptionTable& body_fit_option_table();
// Whether the header turns the body fit on (fit.enabled). Throws posefuse::Error naming the option
// for a bad value.
bool body_fit_enabled(const v1::SessionHeader& header);
// The other options (fit.enabled aside); throws posefuse::Error naming the option for a bad value.
BodyFitOptions read_body_fit_options(const v1::SessionHeader& header);

}  // namespace posefuse::session
