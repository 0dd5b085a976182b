#include "session/stages/measures_options.hpp"

#include <string>
#include <vector>

#include "common/error.hpp"
#include "session/option_reader.hpp"
#include "session/text_fields.hpp"

namespace posefuse::session {
namespace {

std::vector<std::string> repetition_angle_words() {
  std::vector<std::string> words{"auto"};
  for (int i = 0; i < measures::kAngleCount; ++i)
    words.emplace_back(measures::angle_name(static_cast<measures::Angle>(i)));
  return words;
}

}  // namespace

const OptionTable& measures_option_table() {
  static const OptionTable table = [] {
    const measures::RepetitionOptions reps;
    const measures::JointAngleOptions angles;
    return OptionTable{
        {.key = kMeasuresRepetitionAngleKey,
         .type = OptionType::kChoice,
         .default_value = "auto",
         .words = repetition_angle_words(),
         .description = "the angle repetitions are counted on; auto: the arm or trunk angle that moves most"},
        {.key = kMeasuresHysteresisKey,
         .type = OptionType::kReal,
         .default_value = format_double(reps.hysteresis_deg),
         .min = above(0),
         .unit = "deg",
         .description = "smallest reversal of the angle that makes a turning point"},
        {.key = kMeasuresMinAmplitudeKey,
         .type = OptionType::kReal,
         .default_value = format_double(reps.min_amplitude_deg),
         .min = above(0),
         .unit = "deg",
         .description = "a swing this large always counts; an angle that moves less than twice this needs "
                        "half its motion (5th to 95th percentile), at least twice hysteresis_deg; smaller swings "
                        "are partial. With repetition_angle auto, the spread an angle confident in half its frames "
                        "needs to be chosen over unsure ones"},
        {.key = kMeasuresMinDurationKey,
         .type = OptionType::kReal,
         .default_value = format_double(reps.min_duration_s),
         .min = at_least(0),
         .unit = "s",
         .description = "shortest counted repetition, trough to trough"},
        {.key = kMeasuresMaxDurationKey,
         .type = OptionType::kReal,
         .default_value = format_double(reps.max_duration_s),
         .min = above(0),
         .unit = "s",
         .description = "longest counted repetition, trough to trough"},
        {.key = kMeasuresMaxGapKey,
         .type = OptionType::kReal,
         .default_value = format_double(reps.max_gap_s),
         .min = above(0),
         .unit = "s",
         .description =
             "frames without the angle for longer than this cut the series (the repetition across is partial)"},
        {.key = kMeasuresMinElbowFlexionKey,
         .type = OptionType::kReal,
         .default_value = format_double(angles.min_elbow_flexion_deg),
         .min = at_least(0),
         .max = below(90),
         .unit = "deg",
         .description = "below this elbow flexion the arm spans no plane: no humerus axial rotation or pronation"},
        {.key = kMeasuresMinElevationKey,
         .type = OptionType::kReal,
         .default_value = format_double(angles.min_elevation_for_plane_deg),
         .min = above(0),
         .max = below(90),
         .unit = "deg",
         .description =
             "below this elevation (or above 180 minus it) the plane of elevation is held (Y-X-Y gimbal lock) and "
             "the humerus' axial rotation has confidence 0"},
        {.key = kMeasuresArmLengthUncertaintyKey,
         .type = OptionType::kReal,
         .default_value = format_double(angles.arm_length_uncertainty),
         .min = at_least(0),
         .max = below(0.5),
         .description = "relative RMS error of the fitted arm lengths; the elbow flexion's confidence carries the "
                        "spread it gives near full extension"},
        {.key = kMeasuresJointPositionUncertaintyKey,
         .type = OptionType::kReal,
         .default_value = format_double(angles.joint_position_uncertainty_m),
         .min = at_least(0),
         .max = at_most(0.2),
         .unit = "m",
         .description =
             "RMS error of a fitted joint's position; the confidence of the thorax angles (the flexion and axial "
             "rotation most with the trunk tilted far to the side), of the elevation, of the plane of elevation "
             "(most near the gimbal lock) and of the humerus' axial rotation (most near a straight elbow or the "
             "lock) carries the spread it gives"},
        {.key = kMeasuresGirdleElevationUncertaintyKey,
         .type = OptionType::kReal,
         .default_value = format_double(angles.girdle_elevation_uncertainty_deg),
         .min = at_least(0),
         .max = at_most(90),
         .unit = "deg",
         .description = "RMS error of the fitted girdle elevation (the collars have no camera joint); its "
                        "confidence is at most what this allows"},
    };
  }();
  return table;
}

MeasuresOptions read_measures_options(const v1::SessionHeader& header) {
  const OptionReader options(measures_option_table(), header);
  MeasuresOptions out;
  out.repetitions.hysteresis_deg = options.real(kMeasuresHysteresisKey);
  out.repetitions.min_amplitude_deg = options.real(kMeasuresMinAmplitudeKey);
  out.repetitions.min_duration_s = options.real(kMeasuresMinDurationKey);
  out.repetitions.max_duration_s = options.real(kMeasuresMaxDurationKey);
  out.repetitions.max_gap_s = options.real(kMeasuresMaxGapKey);
  out.angles.min_elbow_flexion_deg = options.real(kMeasuresMinElbowFlexionKey);
  out.angles.min_elevation_for_plane_deg = options.real(kMeasuresMinElevationKey);
  out.angles.arm_length_uncertainty = options.real(kMeasuresArmLengthUncertaintyKey);
  out.angles.joint_position_uncertainty_m = options.real(kMeasuresJointPositionUncertaintyKey);
  out.angles.girdle_elevation_uncertainty_deg = options.real(kMeasuresGirdleElevationUncertaintyKey);
  for (int i = 0; i < measures::kAngleCount; ++i) {
    const auto angle = static_cast<measures::Angle>(i);
    if (options.choice_is(kMeasuresRepetitionAngleKey, measures::angle_name(angle))) out.repetition_angle = angle;
  }
  // The segmentation's own checks (min_amplitude >= hysteresis, min <= max duration) name
  // repetition_options.*; checked here too so that a bad header fails at the start.
  if (out.repetitions.min_amplitude_deg < out.repetitions.hysteresis_deg)
    throw Error(ErrorCode::kInvalidArgument, option_field(kMeasuresMinAmplitudeKey),
                "must be at least " + std::string(kMeasuresHysteresisKey));
  if (out.repetitions.min_duration_s > out.repetitions.max_duration_s)
    throw Error(ErrorCode::kInvalidArgument, option_field(kMeasuresMaxDurationKey),
                "must be at least " + std::string(kMeasuresMinDurationKey));
  return out;
}

}  // namespace posefuse::session
