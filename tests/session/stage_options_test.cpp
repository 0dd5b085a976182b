// The stages' option tables: every option declared once, its default readable, and every option
// reaching what the stage uses (read_imu_options, read_forearm_options, read_body_fit_options).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <numbers>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "common/error.hpp"
#include "session/mag_calibration_option.hpp"
#include "session/stages/body_fit_options.hpp"
#include "session/stages/default_stages.hpp"
#include "session/stages/forearm_options.hpp"
#include "session/stages/imu_options.hpp"
#include "sync/buzzer_stop.hpp"

namespace posefuse::session {
namespace {

v1::SessionHeader header_with(const std::map<std::string, std::string>& options) {
  v1::SessionHeader header;
  for (const auto& [key, value] : options) (*header.mutable_options())[key] = value;
  return header;
}

void expect_field(const std::function<void()>& read, const std::string& key) {
  try {
    read();
    ADD_FAILURE() << key << ": accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_EQ(e.field(), "header.options[" + key + "]") << e.what();
  }
}

TEST(StageOptions, EveryKeyIsDeclaredOnceUnderItsStagesPrefix) {
  const std::map<std::string, std::string> prefix{
      {"imu_orientation", "imu."}, {"forearm", "forearm."}, {"body_fit", "fit."}, {"measures", "measures."}};
  std::set<std::string> keys;
  for (const auto& stage : make_default_stages()) {
    for (const OptionSpec& option : stage->options()) {
      SCOPED_TRACE(option.key);
      EXPECT_TRUE(keys.insert(option.key).second) << "declared twice";
      EXPECT_EQ(option.key.rfind(prefix.at(std::string(stage->name())), 0), 0u);
      EXPECT_FALSE(option.description.empty());
      if (option.type == OptionType::kChoice) {
        EXPECT_NE(std::find(option.words.begin(), option.words.end(), option.default_value), option.words.end());
      }
    }
  }
  EXPECT_EQ(keys.size(), 45u);
}

TEST(StageOptions, DefaultsAreValidAndTheLibrariesOwn) {
  const v1::SessionHeader none;
  const ImuOptions imu = read_imu_options(none);
  const imu::RobustOrientationFilter::Params filter;
  EXPECT_EQ(imu.filter.tau_acc_s, filter.tau_acc_s);
  EXPECT_EQ(imu.filter.tau_mag_s, filter.tau_mag_s);
  EXPECT_TRUE(imu.mag_calibrations.empty());

  const ForearmOptions forearm = read_forearm_options(none);
  const forearm::VisualAxisCorrectionOptions correction;
  EXPECT_EQ(forearm.axis_correction.gain_K, correction.gain_K);
  EXPECT_EQ(forearm.axis_correction.gain_F, correction.gain_F);
  EXPECT_NEAR(forearm.axis_correction.max_angle_rad, correction.max_angle_rad, 1e-15);
  EXPECT_EQ(forearm.buzzer_tone_hz, sync::BuzzerStopOptions().tone_hz);
  EXPECT_EQ(forearm.K_from_B, std::nullopt);
  EXPECT_EQ(forearm.body_id, std::nullopt);
  EXPECT_FALSE(forearm.smoother.use_shoulder_sphere);  // 'off' (the table says why)
  EXPECT_TRUE(forearm.fit_anchor);                     // 'auto' with the body fit (on by default)
  EXPECT_TRUE(forearm.axis_from_depth && forearm.upper_arm_from_depth && forearm.pose_orientation &&
              forearm.axis_correction_on);

  EXPECT_TRUE(body_fit_enabled(none));
  const BodyFitOptions fit = read_body_fit_options(none);
  const fit::FitOptions fit_defaults;
  EXPECT_EQ(fit.fit.max_iterations, fit_defaults.max_iterations);
  EXPECT_EQ(fit.fit.lambda_imu, fit_defaults.lambda_imu);
  EXPECT_EQ(fit.fit.freeze_contour_after, fit_defaults.freeze_contour_after);
  EXPECT_EQ(fit.fit.min_joint_step_m, fit_defaults.min_joint_step_m);
  EXPECT_EQ(fit.fit.joint_step_stop_max_damping, fit_defaults.joint_step_stop_max_damping);
  EXPECT_EQ(fit.fit.project_steps_onto_limits, fit_defaults.project_steps_onto_limits);
  EXPECT_EQ(fit.fit.silhouette_edge_px, fit_defaults.silhouette_edge_px);
  EXPECT_EQ(fit.smoothing.window_frames, fit::PoseSmoothingOptions().window_frames);
  EXPECT_EQ(fit.extrapolation.velocity_gain, 0.0);  // off (the table says why)
  EXPECT_NO_THROW(fit::validate(fit.fit));
}

TEST(StageOptions, EveryImuOptionReachesTheStage) {
  v1::SessionHeader header = header_with({{kImuTauAccKey, "2.5"}, {kImuTauMagKey, "7"}});
  header.add_imu_devices()->set_device_id("left");
  header.add_imu_devices()->set_device_id("right");
  imu::MagCalibration calibration;
  calibration.center_uT = imu::Vec3(4, 5, 6);
  (*header.mutable_options())[mag_calibration_option_key("left")] = format_mag_calibration(calibration);
  (*header.mutable_options())[mag_calibration_option_key("other")] = "not read: no such device";
  const ImuOptions o = read_imu_options(header);
  EXPECT_EQ(o.filter.tau_acc_s, 2.5);
  EXPECT_EQ(o.filter.tau_mag_s, 7.0);
  ASSERT_EQ(o.mag_calibrations.size(), 1u);
  EXPECT_EQ(o.mag_calibrations.at("left").center_uT, calibration.center_uT);
}

TEST(StageOptions, EveryForearmOptionReachesTheStage) {
  const ForearmOptions o = read_forearm_options(header_with({{kForearmKFromBKey, "0 1 0 0"},
                                                             {kForearmCalibrationSKey, "7"},
                                                             {kForearmCalibrationOrientationKey, "sdk"},
                                                             {kForearmBodyIdKey, "4"},
                                                             {kForearmAxisKey, "sdk"},
                                                             {kForearmShoulderSphereKey, "on"},
                                                             {kForearmUpperArmKey, "sdk"},
                                                             {kForearmBuzzerHzKey, "auto"},
                                                             {kForearmGapAnchorKey, "sdk"},
                                                             {kFitEnabledKey, "true"},
                                                             {kForearmAxisCorrectionKey, "off"},
                                                             {kForearmAxisCorrectionGainKKey, "0.1"},
                                                             {kForearmAxisCorrectionGainFKey, "0.3"},
                                                             {kForearmAxisCorrectionMaxDegKey, "10"}}));
  ASSERT_TRUE(o.K_from_B);
  EXPECT_EQ(o.K_from_B->x(), 1.0);
  EXPECT_EQ(o.calibration_s, 7.0);
  EXPECT_FALSE(o.pose_orientation);
  EXPECT_EQ(o.body_id, 4u);
  EXPECT_FALSE(o.axis_from_depth);
  EXPECT_TRUE(o.smoother.use_shoulder_sphere);
  EXPECT_FALSE(o.upper_arm_from_depth);
  EXPECT_EQ(o.buzzer_tone_hz, std::nullopt);
  EXPECT_FALSE(o.fit_anchor);  // sdk, though the fit runs
  EXPECT_FALSE(o.axis_correction_on);
  EXPECT_EQ(o.axis_correction.gain_K, 0.1);
  EXPECT_EQ(o.axis_correction.gain_F, 0.3);
  EXPECT_DOUBLE_EQ(o.axis_correction.max_angle_rad, 10.0 * std::numbers::pi / 180.0);

  EXPECT_TRUE(read_forearm_options(header_with({{kFitEnabledKey, "true"}})).fit_anchor);
  EXPECT_EQ(read_forearm_options(header_with({{kForearmBuzzerHzKey, "3000"}})).buzzer_tone_hz, 3000.0);
}

TEST(StageOptions, ForearmChecksAcrossOptionsNameTheOptionSet) {
  // The gains' sum: named after the gain the header set.
  expect_field(
      [] {
        read_forearm_options(header_with({{kForearmAxisCorrectionGainFKey, "0.99"}}));
      },
      kForearmAxisCorrectionGainFKey);
  expect_field(
      [] {
        read_forearm_options(header_with({{kForearmAxisCorrectionGainKKey, "0.99"}}));
      },
      kForearmAxisCorrectionGainKKey);
  expect_field(
      [] {
        read_forearm_options(
            header_with({{kForearmAxisCorrectionGainKKey, "0"}, {kForearmAxisCorrectionGainFKey, "0"}}));
      },
      kForearmAxisCorrectionGainKKey);
  // The buzzer below half the audio rate.
  v1::SessionHeader audio = header_with({{kForearmBuzzerHzKey, "4000"}});
  audio.set_audio_sample_rate_hz(8000);
  expect_field([&] { read_forearm_options(audio); }, kForearmBuzzerHzKey);
  (*audio.mutable_options())[kForearmBuzzerHzKey] = "3999";
  EXPECT_EQ(read_forearm_options(audio).buzzer_tone_hz, 3999.0);
  // gap_anchor is checked whether or not the fit runs.
  expect_field([] { read_forearm_options(header_with({{kForearmGapAnchorKey, "fit"}})); }, kForearmGapAnchorKey);
}

TEST(StageOptions, EveryBodyFitOptionReachesTheStage) {
  const BodyFitOptions o = read_body_fit_options(header_with({{kFitCalibrationSKey, "2"},
                                                              {kFitBodyIdKey, "3"},
                                                              {kFitSmoothingFramesKey, "5"},
                                                              {kFitImuWaitSKey, "12"},
                                                              {kFitLostEnergyKey, "80"},
                                                              {kFitTrustedEnergyKey, "30"},
                                                              {kFitMaxIterationsKey, "11"},
                                                              {kFitFineShapeKey, "false"},
                                                              {kFitLambdaImuKey, "0"},
                                                              {kFitSkeletonStartEnergyKey, "0"},
                                                              {kFitFreezeContourAfterKey, "0"},
                                                              {kFitMinJointStepMKey, "0.004"},
                                                              {kFitJointStepStopMaxDampingKey, "1e8"},
                                                              {kFitProjectStepsOntoLimitsKey, "false"},
                                                              {kFitSilhouetteEdgePxKey, "1.25"},
                                                              {kFitStartVelocityGainKey, "1"}}));
  EXPECT_EQ(o.calibration_s, 2.0);
  EXPECT_EQ(o.body_id, 3u);
  EXPECT_EQ(o.smoothing.window_frames, 5);
  EXPECT_EQ(o.imu_wait_s, 12.0);
  EXPECT_EQ(o.lost_energy, 80.0);
  EXPECT_EQ(o.trusted_energy, 30.0);
  EXPECT_EQ(o.fit.max_iterations, 11);
  EXPECT_FALSE(o.fine_shape);
  EXPECT_EQ(o.fit.lambda_imu, 0.0);
  EXPECT_EQ(o.skeleton_start_energy, 0.0);
  EXPECT_EQ(o.fit.freeze_contour_after, 0);
  EXPECT_EQ(o.fit.min_joint_step_m, 0.004);
  EXPECT_EQ(o.fit.joint_step_stop_max_damping, 1e8);
  EXPECT_FALSE(o.fit.project_steps_onto_limits);
  EXPECT_EQ(o.fit.silhouette_edge_px, 1.25);
  EXPECT_EQ(o.extrapolation.velocity_gain, 1.0);
  EXPECT_TRUE(body_fit_enabled(header_with({{kFitEnabledKey, "1"}})));
}

TEST(StageOptions, BodyFitBadValuesNameTheOption) {
  for (const auto& option : std::vector<std::pair<std::string, std::string>>{{kFitSmoothingFramesKey, "2"},
                                                                             {kFitSmoothingFramesKey, "0"},
                                                                             {kFitMaxIterationsKey, "-1"},
                                                                             {kFitBodyIdKey, "-2"},
                                                                             {kFitLostEnergyKey, "0"},
                                                                             {kFitTrustedEnergyKey, "0"},
                                                                             {kFitMinJointStepMKey, "-0.001"},
                                                                             {kFitSilhouetteEdgePxKey, "-1"},
                                                                             {kFitSilhouetteEdgePxKey, "17"}}) {
    expect_field([&] { read_body_fit_options(header_with({option})); }, option.first);
  }
  expect_field([] { body_fit_enabled(header_with({{kFitEnabledKey, "maybe"}})); }, kFitEnabledKey);
}

}  // namespace
}  // namespace posefuse::session
