// posefuse-sim's options file: every key is applied, every error names the file, line, key and
// the value.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "common/error.hpp"
#include "sim/exercises.hpp"
#include "tools/sim/sim_options_file.hpp"

using namespace posefuse;
using posefuse::tools::apply_sim_options;

namespace {

// The error apply_sim_options throws for `text`, or a failure.
Error error_of(const std::string& text) {
  sim::SimSessionOptions options;
  try {
    apply_sim_options(text, "opts.txt", options);
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << "no error for: " << text;
  return Error(ErrorCode::kInternal, "", "");
}

}  // namespace

TEST(SimOptionsFile, AppliesEveryKindOfValue) {
  sim::SimSessionOptions options;
  apply_sim_options(
      "# a comment\n"
      "seed = 42\n"
      "duration_s = 12.5   # trailing comment\n"
      "\n"
      "  sex=female\n"
      "betas = 0.5, -1, 2\n"
      "heading_deg = 90\n"
      "color = false\n"
      "color_width = 480\n"
      "imu_arms = left\r\n"
      "imu_roles_swapped = true\n"
      "buzzer_tone_hz = 3400\n"
      "strap_slip = off\n"
      "clothing_subdivisions = 2\n"
      "packet_loss_rate = 0.05\n"
      "imu_errors = false\n"
      "clock_drift_max_ppm = 20\n"
      "motion = forearm_rolling\n"
      "speed = 1.5\n"
      "repetitions = 2\n"
      "arm = both\n"
      "bvh_path = /tmp/clip.bvh\n"
      "calibration_prefix = true\n"
      "calibration_suffix = true\n"
      "gyro_range_dps = 1000\n"
      "bvh_smoothing = noise_level\n"
      "bvh_max_glitch_frames = 30\n"
      "bvh_max_joint_rate_rad_s = 80\n"
      "acc_range_g = 8\n"
      "imu_warm_up_K = 8\n"
      "imu_warm_up_time_constant_s = 120\n"
      "threads = 3\n",
      "opts.txt", options);
  EXPECT_EQ(options.seed, 42u);
  EXPECT_DOUBLE_EQ(options.duration_s, 12.5);
  EXPECT_EQ(options.sex, body::Sex::kFemale);
  ASSERT_EQ(options.betas.size(), 10);
  EXPECT_DOUBLE_EQ(options.betas[0], 0.5);
  EXPECT_DOUBLE_EQ(options.betas[1], -1.0);
  EXPECT_DOUBLE_EQ(options.betas[2], 2.0);
  EXPECT_DOUBLE_EQ(options.betas[3], 0.0);
  EXPECT_NEAR(options.heading_rad, 3.14159265358979 / 2, 1e-12);
  EXPECT_FALSE(options.color);
  EXPECT_EQ(options.color_camera.intrinsics.width, 480);
  EXPECT_EQ(options.color_camera.intrinsics.height, 270);
  EXPECT_DOUBLE_EQ(options.color_camera.intrinsics.fx, 264.0);
  EXPECT_TRUE(options.arm_imu[0]);
  EXPECT_FALSE(options.arm_imu[1]);
  EXPECT_TRUE(options.arm_imu_roles_swapped);
  EXPECT_FALSE(options.strap_slip.enabled);
  EXPECT_EQ(options.clothing.subdivisions, 2);
  EXPECT_DOUBLE_EQ(options.imu.packet_loss.loss_rate, 0.05);
  EXPECT_EQ(options.imu.synth.error_model.gyr_bias_sigma_rad_s, 0.0);
  EXPECT_DOUBLE_EQ(options.clock_drift_max, 20e-6);
  EXPECT_EQ(options.motion, "forearm_rolling");
  EXPECT_DOUBLE_EQ(options.motion_options.exercise.speed, 1.5);
  EXPECT_EQ(options.motion_options.exercise.repetitions, 2);
  EXPECT_EQ(options.motion_options.exercise.arm, sim::ExerciseArm::kBoth);
  EXPECT_EQ(options.motion_options.bvh_path, "/tmp/clip.bvh");
  EXPECT_TRUE(options.motion_options.calibration_prefix);
  EXPECT_TRUE(options.motion_options.calibration_suffix);
  EXPECT_EQ(options.threads, 3);
  EXPECT_DOUBLE_EQ(options.buzzer.tone_hz, 3400.0);
  EXPECT_DOUBLE_EQ(options.imu.synth.gyr_range_rad_s, 1000 * 3.14159265358979323846 / 180);
  EXPECT_DOUBLE_EQ(options.imu.synth.acc_range_m_s2, 8 * 9.80665);
  EXPECT_DOUBLE_EQ(options.imu.synth.warm_up.rise_K, 8.0);
  EXPECT_DOUBLE_EQ(options.imu.synth.warm_up.time_constant_s, 120.0);
  EXPECT_FALSE(options.duration_from_motion);
  EXPECT_EQ(options.motion_options.bvh_smoothing, sim::BvhSmoothing::kNoiseLevel);
  EXPECT_EQ(options.motion_options.bvh_glitches.max_glitch_frames, 30);
  EXPECT_DOUBLE_EQ(options.motion_options.bvh_glitches.max_joint_rate_rad_s, 80.0);
  EXPECT_NO_THROW(sim::validate(options));
}

TEST(SimOptionsFile, DurationClipTakesTheMotionsLength) {
  sim::SimSessionOptions options;
  apply_sim_options("duration_s = clip\n", "opts.txt", options);
  EXPECT_TRUE(options.duration_from_motion);
  EXPECT_NO_THROW(sim::validate(options));
  // A later number (the --duration flag) replaces it.
  posefuse::tools::apply_sim_option("duration_s", "5", "--duration", options);
  EXPECT_FALSE(options.duration_from_motion);
  EXPECT_DOUBLE_EQ(options.duration_s, 5.0);
  // An exercise's own length: arm_raising's is 3 repetitions at speed 1.
  apply_sim_options("duration_s = clip\nmotion = arm_raising\nspeed = 2\n", "opts.txt", options);
  const sim::SimSessionOptions settled = sim::with_session_duration(options);
  EXPECT_FALSE(settled.duration_from_motion);
  EXPECT_DOUBLE_EQ(settled.duration_s, sim::make_exercise("arm_raising", options.motion_options.exercise).duration_s);
  EXPECT_GT(settled.duration_s, 1.0);
}

TEST(SimOptionsFile, ErrorsNameFileLineKeyAndValue) {
  struct Case {
    std::string text, field, message_part;
  };
  const std::vector<Case> cases = {
      {"seed = 1\nfoo = 3\n", "opts.txt:2:foo", "unknown key 'foo'"},
      {"duration_s = ten\n", "opts.txt:1:duration_s", "value 'ten' is not a finite number"},
      {"duration_s = nan\n", "opts.txt:1:duration_s", "value 'nan'"},
      {"duration_s = 0.5\n", "opts.txt:1:duration_s", "value '0.5' must be in 1..3600"},
      {"seed = -3\n", "opts.txt:1:seed", "value '-3' is not an unsigned integer"},
      {"sex = robot\n", "opts.txt:1:sex", "value 'robot' must be male or female"},
      {"motion = dancing\n", "opts.txt:1:motion", "value 'dancing' is not a known motion"},
      {"speed = 0\n", "opts.txt:1:speed", "value '0' must be > 0"},
      {"repetitions = 0\n", "opts.txt:1:repetitions", "value '0' must be in 1..1000"},
      {"arm = middle\n", "opts.txt:1:arm", "value 'middle' must be right, left or both"},
      {"color = maybe\n", "opts.txt:1:color", "value 'maybe' is not a boolean"},
      {"color_width = 12\n", "opts.txt:1:color_width", "value '12' must be in 64..1920"},
      {"betas = 1,,2\n", "opts.txt:1:betas", "value '' is not a finite number"},
      {"betas = 1,2,3,4,5,6,7,8,9,10,11\n", "opts.txt:1:betas", "has more than 10 values"},
      {"packet_loss_rate = 1.5\n", "opts.txt:1:packet_loss_rate", "must be in [0, 1]"},
      {"imu_arms = three\n", "opts.txt:1:imu_arms", "value 'three'"},
      {"threads = 0\n", "opts.txt:1:threads", "value '0' must be in 1..64"},
      {"duration_s = clips\n", "opts.txt:1:duration_s", "value 'clips' is not a finite number"},
      {"gyro_range_dps = 100\n", "opts.txt:1:gyro_range_dps", "value '100' must be in 125..4000"},
      {"acc_range_g = 64\n", "opts.txt:1:acc_range_g", "value '64' must be in 2..32"},
      {"imu_warm_up_K = 30\n", "opts.txt:1:imu_warm_up_K", "value '30' must be in 0..20"},
      {"imu_warm_up_K = -1\n", "opts.txt:1:imu_warm_up_K", "value '-1'"},
      {"imu_warm_up_time_constant_s = 0.5\n", "opts.txt:1:imu_warm_up_time_constant_s",
       "value '0.5' must be in 1..3600"},
      {"bvh_max_glitch_frames = 0\n", "opts.txt:1:bvh_max_glitch_frames", "value '0' must be in 1..600"},
      {"bvh_max_joint_rate_rad_s = 5\n", "opts.txt:1:bvh_max_joint_rate_rad_s", "value '5' must be in 10..1000"},
      {"bvh_smoothing = median\n", "opts.txt:1:bvh_smoothing", "value 'median' must be gaussian or noise_level"},
      {"ble_repeat_s = 0.5\n", "opts.txt:1:ble_repeat_s", "must be 0 or >= 1"},
      {"buzzer_repeat_s = 1\n", "opts.txt:1:buzzer_repeat_s", "must be 0 or >= 2"},
      {"buzzer_tone_hz = 9000\n", "opts.txt:1:buzzer_tone_hz", "must be in [200, 7900] Hz"},
      {"seed = 1\nseed = 2\n", "opts.txt:2:seed", "is set twice"},
      {"\n\njust words\n", "opts.txt:3", "expected 'key = value'"},
      {"seed =\n", "opts.txt:1:seed", "has no value"},
      {"= 4\n", "opts.txt:1", "empty key"},
  };
  for (const Case& c : cases) {
    const Error e = error_of(c.text);
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument) << c.text;
    EXPECT_EQ(e.field(), c.field) << c.text;
    EXPECT_NE(std::string(e.what()).find(c.message_part), std::string::npos) << c.text << " -> " << e.what();
  }
}

TEST(SimOptionsFile, EveryKeyIsListedWithItsMeaning) {
  const auto& keys = tools::sim_option_keys();
  EXPECT_GE(keys.size(), 30u);
  for (const auto& key : keys) EXPECT_GT(std::string(key.meaning).size(), 5u) << key.key;
}

TEST(SimOptionsFile, MissingFileIsNotFound) {
  sim::SimSessionOptions options;
  try {
    tools::apply_sim_options_file("/nonexistent/opts.txt", options);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kNotFound);
  }
}

TEST(SimOptionsFile, BvhJointMapIsBuiltInOrAFileWhoseErrorsNameItsLine) {
  sim::SimSessionOptions options;
  EXPECT_EQ(options.motion_options.bvh_joint_map.source, "auto");
  apply_sim_options("bvh_joint_map = cmu31\n", "opts.txt", options);
  EXPECT_EQ(options.motion_options.bvh_joint_map.source, "cmu31");
  EXPECT_EQ(options.motion_options.bvh_joint_map.entries.size(), 22u);
  EXPECT_TRUE(options.motion_options.bvh_joint_map.strict);

  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "posefuse_sim_options_joint_map";
  std::filesystem::create_directories(dir);
  const std::filesystem::path map = dir / "rig.map";
  std::ofstream(map) << "pelvis = Hips\nleft_hip = Hips\n";
  const Error e = error_of("bvh_joint_map = " + map.string() + "\n");
  EXPECT_EQ(e.field(), map.string() + ":2");
  EXPECT_NE(std::string(e.what()).find("BVH joint 'Hips' already drives 'pelvis' (line 1)"), std::string::npos)
      << e.what();
  const Error missing = error_of("bvh_joint_map = " + (dir / "none.map").string() + "\n");
  EXPECT_EQ(missing.code(), ErrorCode::kNotFound);
  EXPECT_EQ(missing.field(), (dir / "none.map").string());
  std::filesystem::remove_all(dir);
}
