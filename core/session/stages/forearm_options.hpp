#pragma once
// The forearm stage's SessionHeader.options: their table and what they hold.
#include <cstdint>
#include <optional>

#include <Eigen/Geometry>

#include "forearm/gap_smoother.hpp"
#include "forearm/visual_axis_correction.hpp"
#include "posefuse/v1/session.pb.h"
#include "session/option_table.hpp"

namespace posefuse::session {

inline constexpr const char* kForearmKFromBKey = "forearm.K_from_B";
inline constexpr const char* kForearmCalibrationSKey = "forearm.calibration_s";
inline constexpr const char* kForearmCalibrationOrientationKey = "forearm.calibration_orientation";
inline constexpr const char* kForearmBodyIdKey = "forearm.body_id";
inline constexpr const char* kForearmAxisKey = "forearm.axis";
inline constexpr const char* kForearmShoulderSphereKey = "forearm.shoulder_sphere";
inline constexpr const char* kForearmUpperArmKey = "forearm.upper_arm";
inline constexpr const char* kForearmBuzzerHzKey = "forearm.buzzer_hz";
inline constexpr const char* kForearmGapAnchorKey = "forearm.gap_anchor";
inline constexpr const char* kForearmAxisCorrectionKey = "forearm.axis_correction";
inline constexpr const char* kForearmAxisCorrectionGainKKey = "forearm.axis_correction_gain_K";
inline constexpr const char* kForearmAxisCorrectionGainFKey = "forearm.axis_correction_gain_F";
inline constexpr const char* kForearmAxisCorrectionMaxDegKey = "forearm.axis_correction_max_deg";

// What the options say, as the stage uses it. The defaults are the table's (read_forearm_options).
struct ForearmOptions {
  std::optional<Eigen::Quaterniond> K_from_B;            // forearm.K_from_B; none: no camera alignment (eq. 7)
  double calibration_s = 0;                              // forearm.calibration_s
  bool pose_orientation = false;                         // forearm.calibration_orientation = pose
  std::optional<std::uint32_t> body_id;                  // forearm.body_id; none: the first body in the stream
  bool axis_from_depth = false;                          // forearm.axis = depth
  bool upper_arm_from_depth = false;                     // forearm.upper_arm = depth
  forearm::GapSmootherOptions smoother;                  // use_shoulder_sphere: forearm.shoulder_sphere = on
  std::optional<double> buzzer_tone_hz;                  // forearm.buzzer_hz; none: auto
  bool fit_anchor = false;                               // forearm.gap_anchor = auto and fit.enabled
  bool axis_correction_on = false;                       // forearm.axis_correction = auto
  forearm::VisualAxisCorrectionOptions axis_correction;  // forearm.axis_correction_gain_K, _gain_F, _max_deg
};

const OptionTable& forearm_option_table();
// Throws posefuse::Error naming the option for a bad value, also for the checks that span two
// options (the gains' sum) or the header (the buzzer below half the audio rate).
ForearmOptions read_forearm_options(const v1::SessionHeader& header);

}  // namespace posefuse::session
