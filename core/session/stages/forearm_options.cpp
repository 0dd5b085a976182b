#include "session/stages/forearm_options.hpp"

#include <limits>
#include <numbers>
#include <string>

#include "common/error.hpp"
#include "session/option_reader.hpp"
#include "session/stages/body_fit_options.hpp"
#include "session/text_fields.hpp"
#include "sync/buzzer_stop.hpp"

namespace posefuse::session {

const OptionTable& forearm_option_table() {
  static const OptionTable table = [] {
    const forearm::VisualAxisCorrectionOptions axis_correction;
    return OptionTable{
        {.key = kForearmKFromBKey,
         .type = OptionType::kQuaternion,
         .description = "base IMU orientation in the camera frame (paper 1 eq. 8); required"},
        // The upper bound keeps the window's end (first frame + calibration_s in us) far from
        // int64 overflow and the samples kept for the search bounded.
        {.key = kForearmCalibrationSKey,
         .type = OptionType::kReal,
         .default_value = "5",
         .min = above(0),
         .max = at_most(120),
         .unit = "s",
         .description = "the calibration pose is searched for within this time after the first skeleton frame"},
        {.key = kForearmCalibrationOrientationKey,
         .type = OptionType::kChoice,
         .default_value = "pose",
         .words = {"pose", "sdk"},
         .description = "forearm orientation in the calibration pose: 'pose' (arm plane, palm to the camera) or 'sdk' "
                        "(SDK wrist, eq. 9)"},
        {.key = kForearmBodyIdKey,
         .type = OptionType::kInteger,
         .min = at_least(0),
         .max = at_most(std::numeric_limits<std::uint32_t>::max()),
         .description = "skeleton body id to follow; default: the first one in the stream"},
        {.key = kForearmAxisKey,
         .type = OptionType::kChoice,
         .default_value = "depth",
         .words = {"depth", "sdk"},
         .description = "forearm axis (elbow, wrist) for the calibration frame, strap detection, II-J tests and "
                        "eq. 10: 'depth' (fitted to the depth image around the SDK segment, forearm_axis_depth.hpp) "
                        "or 'sdk' (the SDK joints, paper 1)"},
        {.key = kForearmShoulderSphereKey,
         .type = OptionType::kChoice,
         .default_value = "off",
         .words = {"on", "off"},
         .description = "'on': the gap smoother keeps the elbow on the sphere of radius d_ul around the SDK shoulder "
                        "(eq. 13); 'off' (default): a real SDK's shoulder is off by 5-10 cm, which pulls the "
                        "recovered trajectory away"},
        {.key = kForearmUpperArmKey,
         .type = OptionType::kChoice,
         .default_value = "depth",
         .words = {"depth", "sdk"},
         .description = "upper arm direction for the calibration pose's arm plane (the roll of A_from_F about the "
                        "forearm, eq. 9): 'depth' (fitted to the depth image, upper_arm_depth.hpp; the SDK shoulder "
                        "if the depth never shows it) or 'sdk' (the SDK shoulder)"},
        // Below half the audio rate too, checked in read_forearm_options.
        {.key = kForearmBuzzerHzKey,
         .type = OptionType::kReal,
         .default_value = format_double(sync::BuzzerStopOptions().tone_hz),
         .min = above(0),
         .words = {"auto"},
         .unit = "Hz",
         .description = "the base IMU's buzzer frequency (sound-based sync, paper 1 II-G.1), below half the audio "
                        "rate: its tone is measured in the audio within 10 % of it; or 'auto': the loudest tone "
                        "between 500 and 8000 Hz that sounds and stops (sync/tone_search.hpp). Demodulated 100 Hz "
                        "off, a stop is found 0.9 ms late (docs/forearm.md)"},
        {.key = kForearmGapAnchorKey,
         .type = OptionType::kChoice,
         .default_value = "auto",
         .words = {"auto", "sdk"},
         .description = "what the gap smoother's elbow anchor follows inside a gap: 'auto' (the body fit's elbows "
                        "when fit.enabled is true, each gap then waits for the fit's frames; else the camera "
                        "skeleton's) or 'sdk' (the camera skeleton's elbow)"},
        {.key = kForearmAxisCorrectionKey,
         .type = OptionType::kChoice,
         .default_value = "auto",
         .words = {"auto", "off"},
         .description = "'auto': with forearm.axis = depth, every K_from_F is turned slowly towards the depth-fitted "
                        "forearm axis of the VISUAL frames, through a rotation of K (the IMU filter's tilt, also "
                        "applied to the K_from_A a gap integrates) and one of F (the mounting's tilt; the roll about "
                        "the forearm stays as calibrated), visual_axis_correction.hpp; orientations then wait for "
                        "the camera frames up to their time (at most 1 s); 'off': eq. 11 as it is (paper 1)"},
        {.key = kForearmAxisCorrectionGainKKey,
         .type = OptionType::kReal,
         .default_value = format_double(axis_correction.gain_K),
         .min = at_least(0),
         .max = at_most(1),
         .description = "the axis correction's step per VISUAL frame through K, a fraction of the angle"},
        {.key = kForearmAxisCorrectionGainFKey,
         .type = OptionType::kReal,
         .default_value = format_double(axis_correction.gain_F),
         .min = at_least(0),
         .max = at_most(1),
         .description = "the axis correction's step per VISUAL frame through F, a fraction of the angle; the two "
                        "gains sum to at most 1 and more than 0"},
        {.key = kForearmAxisCorrectionMaxDegKey,
         .type = OptionType::kReal,
         .default_value = "8",
         .min = above(0),
         .max = at_most(90),
         .unit = "deg",
         .description = "VISUAL frames whose depth axis is further than this from the corrected IMU axis are not "
                        "used"},
    };
  }();
  return table;
}

ForearmOptions read_forearm_options(const v1::SessionHeader& header) {
  const OptionReader options(forearm_option_table(), header);
  ForearmOptions out;
  out.K_from_B = options.quaternion(kForearmKFromBKey);
  out.calibration_s = options.real(kForearmCalibrationSKey);
  out.pose_orientation = options.choice_is(kForearmCalibrationOrientationKey, "pose");
  if (const auto body_id = options.optional_integer(kForearmBodyIdKey)) {
    out.body_id = static_cast<std::uint32_t>(*body_id);
  }
  out.axis_from_depth = options.choice_is(kForearmAxisKey, "depth");
  out.upper_arm_from_depth = options.choice_is(kForearmUpperArmKey, "depth");
  out.smoother.use_shoulder_sphere = options.choice_is(kForearmShoulderSphereKey, "on");

  if (!options.word(kForearmBuzzerHzKey)) {
    out.buzzer_tone_hz = options.real(kForearmBuzzerHzKey);
    const double nyquist_hz = header.audio_sample_rate_hz() / 2.0;
    if (nyquist_hz > 0.0 && !(*out.buzzer_tone_hz < nyquist_hz)) {
      throw_invalid(option_field(kForearmBuzzerHzKey), "is " + session::quoted(format_double(*out.buzzer_tone_hz)) +
                                                           ", must be below " + format_double(nyquist_hz) +
                                                           " Hz (half the audio rate) or 'auto'");
    }
  }

  const bool anchor_auto = options.choice_is(kForearmGapAnchorKey, "auto");
  out.fit_anchor = anchor_auto && body_fit_enabled(header);
  out.axis_correction_on = options.choice_is(kForearmAxisCorrectionKey, "auto");
  out.axis_correction.gain_K = options.real(kForearmAxisCorrectionGainKKey);
  out.axis_correction.gain_F = options.real(kForearmAxisCorrectionGainFKey);
  if (const double sum = out.axis_correction.gain_K + out.axis_correction.gain_F; !(sum > 0.0 && sum <= 1.0)) {
    // Named after the gain the header set (gain_F when only it was).
    const bool only_F_given =
        options.given(kForearmAxisCorrectionGainFKey) && !options.given(kForearmAxisCorrectionGainKKey);
    throw_invalid(option_field(only_F_given ? kForearmAxisCorrectionGainFKey : kForearmAxisCorrectionGainKKey),
                  std::string("the sum of ") + kForearmAxisCorrectionGainKKey + " and " +
                      kForearmAxisCorrectionGainFKey + " is " + format_double(sum) + ", must be in (0, 1]");
  }
  out.axis_correction.max_angle_rad = options.real(kForearmAxisCorrectionMaxDegKey) * std::numbers::pi / 180.0;
  return out;
}

}  // namespace posefuse::session
