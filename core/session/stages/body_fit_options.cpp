#include "session/stages/body_fit_options.hpp"

#include <limits>
#include <string>

#include "common/error.hpp"
#include "common/number_text.hpp"
#include "fit/fitted_body_frame.hpp"
#include "session/option_reader.hpp"
#include "session/text_fields.hpp"

namespace posefuse::session {

namespace {

constexpr double kMaxInt = std::numeric_limits<int>::max();

}  // namespace

const OptionTable& body_fit_option_table() {
  static const OptionTable table = [] {
    const fit::FitOptions fit_defaults;
    const fit::PoseSmoothingOptions smoothing_defaults;
    return OptionTable{
        {.key = kFitEnabledKey,
         .type = OptionType::kBool,
         .default_value = "true",
         .description = "run the body-model fit (paper 2; about 9-12 ms per depth frame on one core; false: IMU "
                        "orientations, forearms and the camera skeleton only)"},
        // The upper bound (as fit.imu_wait_s's) bounds the frames kept: at 30 Hz 900
        // personalisation frames per session at most.
        {.key = kFitCalibrationSKey,
         .type = OptionType::kReal,
         .default_value = "1",
         .min = above(0),
         .max = at_most(30),
         .unit = "s",
         .description = "personalisation: the first seconds of depth frames (controlled pose)"},
        {.key = kFitBodyIdKey,
         .type = OptionType::kInteger,
         .min = at_least(0),
         .max = at_most(std::numeric_limits<std::uint32_t>::max()),
         .description = "the person to fit (body index / skeleton body_id); default the first skeleton's"},
        // Odd too, checked in read_body_fit_options.
        {.key = kFitSmoothingFramesKey,
         .type = OptionType::kInteger,
         .default_value = std::to_string(smoothing_defaults.window_frames),
         .min = at_least(1),
         .max = at_most(kMaxInt),
         .description = "moving average of the fitted poses over this many frames (odd; 1 = none)"},
        // posefuse-sim's chunk files order IMU batches by the device clock, whose offset (1-100 s)
        // puts them after the camera frames of a short session: with the former 6 s, 70 % of the
        // demo's frames were fitted without the imu term (docs/fitting.md, "Paper 1's protocol").
        // The upper bound bounds the frames kept: at 30 Hz 1800 waiting frames of ~40 kB (72 MB).
        {.key = kFitImuWaitSKey,
         .type = OptionType::kReal,
         .default_value = "30",
         .min = above(0),
         .max = at_most(60),
         .unit = "s",
         .description = "how long a frame waits for its forearm orientations (imu term), in camera time; waiting "
                        "frames keep only their silhouette's depth (~40 kB each)"},
        {.key = kFitLostEnergyKey,
         .type = OptionType::kReal,
         .default_value = "100",
         .min = above(0),
         .description = "frames fitted above this energy (eq. 4) are counted as lost tracking (FIT_LOST)"},
        // Chosen on the joint-angle bench's tuning sessions (docs/fitting.md, "A fit's energy";
        // docs/benchmarks.md, "Fit energy and confidence").
        {.key = kFitTrustedEnergyKey,
         .type = OptionType::kReal,
         .default_value = "10",
         .min = above(0),
         .description = "frames whose smoothing window (fit.smoothing_frames) holds a fit above this energy "
                        "(eq. 4) give their joints and forearms a confidence of at most " +
                        fixed_text(fit::untrusted_fit_confidence(), 4) +
                        " (FIT_UNTRUSTED); above fit.lost_energy none"},
        {.key = kFitMaxIterationsKey,
         .type = OptionType::kInteger,
         .default_value = std::to_string(fit_defaults.max_iterations),
         .min = at_least(0),
         .max = at_most(kMaxInt),
         .description = "LM iterations per start at most"},
        {.key = kFitFineShapeKey,
         .type = OptionType::kBool,
         .default_value = "true",
         .description = "personalisation: fine shape tuning on a calibration depth frame (paper 2 III-B)"},
        {.key = kFitLambdaImuKey,
         .type = OptionType::kReal,
         .default_value = format_double(fit_defaults.lambda_imu),
         .min = at_least(0),
         .description = "weight of the imu term (eq. 9)"},
        // docs/fitting.md, "Start policy".
        {.key = kFitSkeletonStartEnergyKey,
         .type = OptionType::kReal,
         .default_value = "45",
         .min = at_least(0),
         .description = "II-G: fit the skeleton-built start only when the previous-frame fit ends at this energy or "
                        "above (0 = always both starts, on two threads)"},
        {.key = kFitFreezeContourAfterKey,
         .type = OptionType::kInteger,
         .default_value = std::to_string(fit_defaults.freeze_contour_after),
         .min = at_least(0),
         .max = at_most(kMaxInt),
         .description = "LM: U_bg (bg / float points) is re-selected in the first this many iterations only (0 = "
                        "always)"},
        {.key = kFitMinJointStepMKey,
         .type = OptionType::kReal,
         .default_value = format_double(fit_defaults.min_joint_step_m),
         .min = at_least(0),
         .description = "LM: stop once an accepted step moves none of the 16 bgJoint joints by more than this (m)"},
        {.key = kFitJointStepStopMaxDampingKey,
         .type = OptionType::kReal,
         .default_value = format_double(fit_defaults.joint_step_stop_max_damping),
         .min = above(0),
         .description = "LM: stop on a joint step under fit.min_joint_step_m only after a step damped by at most this "
                        "(1e8 = after any step)"},
        {.key = kFitProjectStepsOntoLimitsKey,
         .type = OptionType::kBool,
         .default_value = fit_defaults.project_steps_onto_limits ? "true" : "false",
         .description = "LM: each trial step clamped to the pose limits widened by 0.1 rad (false = paper 2's soft "
                        "limits alone)"},
        {.key = kFitLineariseDistancesKey,
         .type = OptionType::kBool,
         .default_value = fit_defaults.linearise_distances ? "true" : "false",
         .description = "LM: bg, bgJoint and float linearised as distances to their sliding closest points (false = "
                        "as offsets to held targets, paper 2)"},
        {.key = kFitSilhouetteEdgePxKey,
         .type = OptionType::kReal,
         .default_value = format_double(fit_defaults.silhouette_edge_px),
         .min = at_least(0),
         .max = at_most(16),
         .description = "bg / bgJoint: a model point counts as outside the silhouette only beyond this many pixels "
                        "from the closest silhouette pixel (the body index's misalignment with the depth)"},
        // Off by default: measured, it did not lower the iterations and raised the occluded error
        // (docs/fitting.md, "Start policy").
        {.key = kFitStartVelocityGainKey,
         .type = OptionType::kReal,
         .default_value = "0",
         .min = at_least(0),
         .description = "previous-frame start moved on by this share of the last frames' velocity (0 = off, 1 = "
                        "constant velocity)"},
    };
  }();
  return table;
}

bool body_fit_enabled(const v1::SessionHeader& header) {
  return OptionReader(body_fit_option_table(), header).boolean(kFitEnabledKey);
}

BodyFitOptions read_body_fit_options(const v1::SessionHeader& header) {
  const OptionReader options(body_fit_option_table(), header);
  BodyFitOptions out;
  out.calibration_s = options.real(kFitCalibrationSKey);
  if (const auto body_id = options.optional_integer(kFitBodyIdKey)) out.body_id = static_cast<std::uint32_t>(*body_id);
  out.smoothing.window_frames = static_cast<int>(options.integer(kFitSmoothingFramesKey));
  if (out.smoothing.window_frames % 2 == 0) {
    throw_invalid(option_field(kFitSmoothingFramesKey),
                  "is " + session::quoted(std::to_string(out.smoothing.window_frames)) + ", must be odd");
  }
  out.imu_wait_s = options.real(kFitImuWaitSKey);
  out.lost_energy = options.real(kFitLostEnergyKey);
  out.trusted_energy = options.real(kFitTrustedEnergyKey);
  out.fine_shape = options.boolean(kFitFineShapeKey);
  out.skeleton_start_energy = options.real(kFitSkeletonStartEnergyKey);
  out.fit.max_iterations = static_cast<int>(options.integer(kFitMaxIterationsKey));
  out.fit.lambda_imu = options.real(kFitLambdaImuKey);
  out.fit.freeze_contour_after = static_cast<int>(options.integer(kFitFreezeContourAfterKey));
  out.fit.min_joint_step_m = options.real(kFitMinJointStepMKey);
  out.fit.joint_step_stop_max_damping = options.real(kFitJointStepStopMaxDampingKey);
  out.fit.project_steps_onto_limits = options.boolean(kFitProjectStepsOntoLimitsKey);
  out.fit.linearise_distances = options.boolean(kFitLineariseDistancesKey);
  out.fit.silhouette_edge_px = options.real(kFitSilhouetteEdgePxKey);
  out.extrapolation.velocity_gain = options.real(kFitStartVelocityGainKey);
  return out;
}

}  // namespace posefuse::session
