#pragma once
// The measures stage's SessionHeader.options: their table and what they hold.
#include <optional>

#include "measures/joint_angles.hpp"
#include "measures/repetitions.hpp"
#include "posefuse/v1/session.pb.h"
#include "session/option_table.hpp"

namespace posefuse::session {

inline constexpr const char* kMeasuresRepetitionAngleKey = "measures.repetition_angle";
inline constexpr const char* kMeasuresHysteresisKey = "measures.hysteresis_deg";
inline constexpr const char* kMeasuresMinAmplitudeKey = "measures.min_amplitude_deg";
inline constexpr const char* kMeasuresMinDurationKey = "measures.min_repetition_s";
inline constexpr const char* kMeasuresMaxDurationKey = "measures.max_repetition_s";
inline constexpr const char* kMeasuresMaxGapKey = "measures.max_gap_s";
inline constexpr const char* kMeasuresMinElbowFlexionKey = "measures.min_elbow_flexion_deg";
inline constexpr const char* kMeasuresMinElevationKey = "measures.min_elevation_for_plane_deg";
inline constexpr const char* kMeasuresArmLengthUncertaintyKey = "measures.arm_length_uncertainty";
inline constexpr const char* kMeasuresJointPositionUncertaintyKey = "measures.joint_position_uncertainty_m";
inline constexpr const char* kMeasuresGirdleElevationUncertaintyKey = "measures.girdle_elevation_uncertainty_deg";

struct MeasuresOptions {
  measures::JointAngleOptions angles;
  measures::RepetitionOptions repetitions;
  std::optional<measures::Angle> repetition_angle;  // none: the angle that moves most
};

const OptionTable& measures_option_table();
// Throws posefuse::Error naming the option for a bad value.
MeasuresOptions read_measures_options(const v1::SessionHeader& header);

}  // namespace posefuse::session
