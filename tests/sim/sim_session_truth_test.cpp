// The whole-session simulator's truth is consistent: the IMU (moved by the posed skeleton at
// 1 kHz) sits on the strap of the rendered body's forearm for every motion, frames map as
// documented, and the strap slip stays within its bounds.
#include <gtest/gtest.h>

#include <unistd.h>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "body/smpl_model.hpp"
#include "sim/bvh.hpp"
#include "sim/exercises.hpp"

#include "common/error.hpp"
#include "geometry/quaternion.hpp"
#include "session/session_validator.hpp"
#include "sim/angle_truth.hpp"
#include "sim/sim_session.hpp"
#include "test_camera.hpp"
#include "test_rigs.hpp"

using namespace posefuse;
using namespace posefuse::sim;

namespace {

class ValidatingSink : public session::ChunkSink {
 public:
  void write(const session::SessionChunk& chunk) override { validator.check(chunk); }
  void finish() override {}
  session::SessionValidator validator;
};

SimSessionOptions small(bool slip) {
  SimSessionOptions o;
  o.duration_s = 2.0;
  o.depth_intrinsics = sim::testing::quarter_kinect_intrinsics();
  o.color = false;
  o.strap_slip.enabled = slip;
  o.mount_sigma_rad = 0.0;
  return o;
}

class HeaderSink : public session::ChunkSink {
 public:
  void write(const session::SessionChunk& chunk) override {
    if (chunk.has_header()) header = chunk.header();
  }
  void finish() override {}
  v1::SessionHeader header;
};

double angle_deg(const Quat& a, const Quat& b) { return geometry::angle_between(a, b) * 180.0 / 3.14159265358979; }

}  // namespace

TEST(SimSessionTruth, ImuSitsOnTheRenderedStrap) {
  const SimSessionOptions o = small(false);
  ValidatingSink sink;
  const SimTruth truth = simulate_session(o, sink);
  sink.validator.finish();
  ASSERT_EQ(truth.frames.size(), 61u);
  ASSERT_EQ(truth.devices.size(), 3u);
  double worst_mm = 0, worst_deg = 0;
  for (const SimFrameTruth& frame : truth.frames) {
    for (int arm = 0; arm < 2; ++arm) {
      const auto a = static_cast<std::size_t>(arm);
      const Vec3 x_F = frame.K_from_F[a] * Vec3::UnitX();
      const Vec3 expected_imu = frame.strap_p_K[a] + o.strap_radius_m * x_F;
      worst_mm = std::max(worst_mm, 1e3 * (frame.imu_p_K[a] - expected_imu).norm());
      worst_deg = std::max(worst_deg, angle_deg(frame.K_from_imu[a], frame.K_from_F[a]));  // F_from_A = I
      EXPECT_NEAR(frame.pronation_rad[a], 0.0, 1e-9);  // arm raising does not roll the forearm
      EXPECT_GE(frame.forearm_visible_fraction[a], 0.8) << frame.t_us;
    }
    // The base IMU is fixed on the camera.
    EXPECT_LT(angle_deg(frame.K_from_imu[2], truth.K_from_B), 1e-6);
  }
  std::printf("IMU vs rendered strap: worst %.4f mm, %.5f deg\n", worst_mm, worst_deg);
  EXPECT_LT(worst_mm, 1.0);
  EXPECT_LT(worst_deg, 0.05);
  // The camera is level: W's up is K's up.
  EXPECT_LT((truth.K_from_W * Vec3::UnitZ() - Vec3::UnitY()).norm(), 1e-12);
  // Devices: arm IMUs then the base, with their roles.
  EXPECT_EQ(truth.devices[0].role, v1::ImuDevice::ARM_LEFT);
  EXPECT_EQ(truth.devices[1].role, v1::ImuDevice::ARM_RIGHT);
  EXPECT_EQ(truth.devices[2].role, v1::ImuDevice::BASE);
  EXPECT_GT(truth.buzzer_heard_camera_s, truth.buzzer_stop_camera_s);

  // Per IMU sample (gt/forearm_orientations): the forearm under the strap is the IMU's own
  // orientation (F_from_A = I, no slip), at every sample's true camera time.
  double worst_sample_deg = 0;
  for (std::size_t d = 0; d < 2; ++d) {
    const SimDeviceTruth& device = truth.devices[d];
    ASSERT_EQ(device.K_from_F.size(), device.t_device_us.size());
    ASSERT_EQ(device.pronation_rad.size(), device.t_device_us.size());
    for (std::size_t i = 0; i < device.K_from_F.size(); ++i) {
      worst_sample_deg = std::max(worst_sample_deg, angle_deg(truth.K_from_W * device.W_from_A[i], device.K_from_F[i]));
      EXPECT_NEAR(device.pronation_rad[i], 0.0, 1e-9);
    }
  }
  std::printf("IMU vs forearm per sample: worst %.5f deg\n", worst_sample_deg);
  EXPECT_LT(worst_sample_deg, 0.05);
  EXPECT_TRUE(truth.devices[2].K_from_F.empty());
}

TEST(SimSessionTruth, EveryExerciseGivesAValidSessionWithTheImuOnTheRenderedForearm) {
  for (const std::string& name : exercise_names()) {
    SimSessionOptions o = small(false);
    o.motion = name;
    o.motion_options.exercise.arm = ExerciseArm::kBoth;
    o.motion_options.exercise.speed = 2.0;
    o.motion_options.exercise.rest_hold_s = 0.0;
    o.depth_rate_hz = 10.0;
    o.clothing.subdivisions = 0;
    ValidatingSink sink;
    const SimTruth truth = simulate_session(o, sink);
    sink.validator.finish();
    ASSERT_EQ(truth.frames.size(), 21u) << name;
    double worst_mm = 0, worst_deg = 0, worst_axis_mm = 0, largest_motion_mm = 0;
    double pronation_min = 0, pronation_max = 0;
    const std::array<int, 2> elbow = {body::kLeftElbow, body::kRightElbow};
    const std::array<int, 2> wrist = {body::kLeftWrist, body::kRightWrist};
    for (const SimFrameTruth& frame : truth.frames) {
      for (std::size_t a = 0; a < 2; ++a) {
        // The IMU on the strap of F...
        const Vec3 expected_imu = frame.strap_p_K[a] + o.strap_radius_m * (frame.K_from_F[a] * Vec3::UnitX());
        worst_mm = std::max(worst_mm, 1e3 * (frame.imu_p_K[a] - expected_imu).norm());
        worst_deg = std::max(worst_deg, angle_deg(frame.K_from_imu[a], frame.K_from_F[a]));
        // ...and F on the rendered forearm: origin d_se from the elbow joint, y towards the wrist.
        const Vec3 e = frame.smpl_joints_K.col(elbow[a]), w = frame.smpl_joints_K.col(wrist[a]);
        const Vec3 strap = e + o.strap_to_elbow_m * (w - e).normalized();
        worst_axis_mm = std::max(worst_axis_mm, 1e3 * (frame.strap_p_K[a] - strap).norm());
        EXPECT_GT((frame.K_from_F[a] * Vec3::UnitY()).dot((w - e).normalized()), 1.0 - 1e-9) << name;
        largest_motion_mm = std::max(largest_motion_mm, 1e3 * (frame.imu_p_K[a] - truth.frames[0].imu_p_K[a]).norm());
        pronation_min = std::min(pronation_min, frame.pronation_rad[a]);
        pronation_max = std::max(pronation_max, frame.pronation_rad[a]);
      }
    }
    std::printf(
        "%-26s IMU vs strap %.4f mm %.5f deg, strap vs joints %.4f mm, IMU moved %.0f mm, pronation %.1f..%.1f deg\n",
        name.c_str(), worst_mm, worst_deg, worst_axis_mm, largest_motion_mm, pronation_min * 180 / 3.14159265358979,
        pronation_max * 180 / 3.14159265358979);
    EXPECT_LT(worst_mm, 1.0) << name;
    EXPECT_LT(worst_deg, 0.05) << name;
    EXPECT_LT(worst_axis_mm, 1e-6) << name;
    if (name == "forearm_rolling") {  // the roll reaches the rendered forearm and the IMU: +-60 deg
      EXPECT_GT(pronation_max, 50.0 * 3.14159265358979 / 180) << name;
      EXPECT_LT(pronation_min, -50.0 * 3.14159265358979 / 180) << name;
    }
    if (name != "torso_tilt" && name != "shoulder_lift") {
      EXPECT_GT(largest_motion_mm, 50.0) << name;
    }
  }
}

TEST(SimSessionTruth, StrapSlipStaysWithinItsBounds) {
  const SimSessionOptions o = small(true);
  ValidatingSink sink;
  const SimTruth truth = simulate_session(o, sink);
  double worst_mm = 0, worst_deg = 0;
  for (const SimFrameTruth& frame : truth.frames) {
    for (std::size_t a = 0; a < 2; ++a) {
      const Vec3 expected_imu = frame.strap_p_K[a] + o.strap_radius_m * (frame.K_from_F[a] * Vec3::UnitX());
      worst_mm = std::max(worst_mm, 1e3 * (frame.imu_p_K[a] - expected_imu).norm());
      worst_deg = std::max(worst_deg, angle_deg(frame.K_from_imu[a], frame.K_from_F[a]));
    }
  }
  const double bound_mm = 1e3 * (o.strap_slip.max_slide_m + o.strap_radius_m * o.strap_slip.max_rotation_rad) + 1.0;
  std::printf("with slip: worst %.3f mm (bound %.3f), %.3f deg\n", worst_mm, bound_mm, worst_deg);
  EXPECT_GT(worst_mm, 0.2);  // it does slip
  EXPECT_LT(worst_mm, bound_mm);
  EXPECT_GT(worst_deg, 0.05);
  EXPECT_LT(worst_deg, o.strap_slip.max_rotation_rad * 180 / 3.14159265358979 + 0.05);
}

TEST(SimSessionTruth, BadOptionsNameTheField) {
  const auto field_of = [](SimSessionOptions o) {
    ValidatingSink sink;
    try {
      simulate_session(o, sink);
    } catch (const Error& e) {
      return e.field();
    }
    return std::string("no error");
  };
  SimSessionOptions o = small(false);
  o.duration_s = 0.5;
  EXPECT_EQ(field_of(o), "duration_s");
  o = small(false);
  o.strap_to_elbow_m = 0.3;
  EXPECT_EQ(field_of(o), "strap_to_elbow_m");
  o = small(false);
  o.wall_distance_m = 2.6;
  EXPECT_EQ(field_of(o), "wall_distance_m");
  o = small(false);
  o.motion = "juggling";
  EXPECT_EQ(field_of(o), "motion");
  o = small(false);
  o.motion = "bvh";
  EXPECT_EQ(field_of(o), "bvh_path");
  o = small(false);
  o.motion_options.exercise.speed = -1;
  EXPECT_EQ(field_of(o), "speed");
  o = small(false);
  o.threads = 0;
  EXPECT_EQ(field_of(o), "threads");
  o = small(false);
  o.betas = Eigen::VectorXd::Constant(3, std::nan(""));
  EXPECT_EQ(field_of(o), "betas");
  o = small(false);
  o.buzzer_repeat_s = 1.0;
  EXPECT_EQ(field_of(o), "buzzer_repeat_s");
  o = small(false);
  o.ble.repeat_every_s = 0.05;
  EXPECT_EQ(field_of(o), "ble.repeat_every_s");
}

// Beyond paper 1's single buzzer stop and BLE burst: both repeat through the session when asked.
TEST(SimSessionTruth, RepeatedSyncSignalsThroughTheSession) {
  SimSessionOptions o = small(false);
  o.duration_s = 6.0;
  o.buzzer_repeat_s = 2.0;
  o.ble.repeat_every_s = 2.0;
  struct Events : session::ChunkSink {
    void write(const session::SessionChunk& chunk) override {
      if (chunk.has_sync_event()) events.push_back(chunk.sync_event());
    }
    void finish() override {}
    std::vector<v1::SyncEvent> events;
  } sink;
  const SimTruth truth = simulate_session(o, sink);
  int stops = 0;
  for (const auto& e : sink.events) stops += e.kind() == v1::SyncEvent::BUZZER_STOP;
  // First stop at 1.5 s, a later one at 3.5 s (5.5 s would leave no half second of silence).
  EXPECT_EQ(stops, 2);
  ASSERT_EQ(truth.buzzer_later_stops_camera_s.size(), 1u);
  EXPECT_NEAR(truth.buzzer_later_stops_camera_s[0], 3.5, 1e-4);
  // Bursts at 0.5, 2.5 and 4.5 s.
  ASSERT_FALSE(truth.ble_broadcast_camera_s.empty());
  EXPECT_LT(truth.ble_broadcast_camera_s.front(), 1.0);
  EXPECT_GE(truth.ble_broadcast_camera_s.back(), 4.5);
}

// duration_s = clip: a 1.5 s BVH clip made here (one frame of the right forearm flipped 180
// degrees about its bone, as mocap solves do) gives a session of exactly the clip's length,
// and the repaired glitch comes back as a warning naming its frames.
TEST(SimSessionTruth, DurationClipPlaysTheWholeClipAndReportsItsGlitches) {
  const auto rig = sim::testing::rig21();
  const std::string text = sim::testing::rig_text(rig, 91, 1.0 / 60, [&](int f, int j, int c) {
    const auto& joint = rig[static_cast<std::size_t>(j)];
    if (joint.root) return c == 1 ? 95.0 : 0.0;
    if (joint.name == "RightArm" && c == 0) return -60.0 + 20.0 * std::sin(2 * 3.14159265358979 * 0.7 * f / 60.0);
    if (joint.name == "RightForeArm" && c == 2) return f == 40 ? 180.0 : 0.0;
    return 0.0;
  });
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("posefuse_duration_clip_" + std::to_string(::getpid()) + ".bvh");
  { std::ofstream(path) << text; }
  SimSessionOptions o = small(false);
  o.motion = "bvh";
  o.motion_options.bvh_path = path.string();
  o.duration_from_motion = true;
  ValidatingSink sink;
  const SimTruth truth = simulate_session(o, sink);
  sink.validator.finish();
  std::filesystem::remove(path);
  EXPECT_EQ(truth.options.duration_s, parse_bvh(text).duration_s());  // 90 frame times as written
  EXPECT_NEAR(truth.options.duration_s, 1.5, 1e-9);
  EXPECT_FALSE(truth.options.duration_from_motion);
  EXPECT_EQ(truth.frames.size(), 46u);  // 0..1.5 s at 30 Hz
  ASSERT_EQ(truth.warnings.size(), 1u);
  std::printf("%s\n", truth.warnings[0].c_str());
  EXPECT_NE(truth.warnings[0].find("bvh frames 40..40 (0.667..0.667 s), RightForeArm"), std::string::npos)
      << truth.warnings[0];

  // Shorter than a session may be: refused naming duration_s and the clip's length.
  o.motion_options.exercise.speed = 2.0;  // plays the 1.5 s clip in 0.75 s
  { std::ofstream(path) << text; }
  try {
    ValidatingSink unused;
    simulate_session(o, unused);
    ADD_FAILURE() << "a 0.75 s session was simulated";
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "duration_s");
    EXPECT_NE(std::string(e.what()).find("0.75"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
}

// gt/'s joint angles and repetitions come from the true pose: arm raising with both arms, three
// times, reads three counted repetitions of an elevation from the rest (8 deg out) to 150 deg.
// A camera tilted on its stand turns the world in K, not the world: W's up in K is the level
// camera's turned by the pitch and roll, the IMUs still sit on the rendered straps, and the true
// angles (read against the true vertical) are those of the level camera.
TEST(SimSessionTruth, ATiltedCameraTurnsTheRoomInKNotTheAngles) {
  SimSessionOptions level = small(false);
  level.motion = "torso_tilt";
  SimSessionOptions tilted = level;
  tilted.camera_pitch_deg = 12;
  tilted.camera_roll_deg = -4;
  ValidatingSink level_sink, tilted_sink;
  const SimTruth level_truth = simulate_session(level, level_sink);
  const SimTruth tilted_truth = simulate_session(tilted, tilted_sink);
  tilted_sink.validator.finish();
  constexpr double kDeg = 3.14159265358979323846 / 180;
  const Vec3 up_K = tilted_truth.K_from_W * Vec3::UnitZ();
  EXPECT_NEAR(std::asin(-up_K.z()) / kDeg, 12, 1e-9);             // pitched down
  EXPECT_NEAR(std::atan2(-up_K.x(), up_K.y()) / kDeg, -4, 1e-9);  // rolled
  for (const SimFrameTruth& frame : tilted_truth.frames) {
    for (std::size_t a = 0; a < 2; ++a) EXPECT_LT(angle_deg(frame.K_from_imu[a], frame.K_from_F[a]), 0.05);
  }
  const AngleTruth level_angles = angle_truth(level_truth), tilted_angles = angle_truth(tilted_truth);
  ASSERT_EQ(level_angles.frames.size(), tilted_angles.frames.size());
  double worst_deg = 0;
  for (std::size_t f = 0; f < level_angles.frames.size(); ++f) {
    for (int i = 0; i < measures::kAngleCount; ++i) {
      const measures::AngleValue& l = level_angles.frames[f][static_cast<std::size_t>(i)];
      const measures::AngleValue& t = tilted_angles.frames[f][static_cast<std::size_t>(i)];
      ASSERT_EQ(l.defined, t.defined);
      if (l.defined) worst_deg = std::max(worst_deg, std::abs(l.deg - t.deg));
    }
  }
  EXPECT_LT(worst_deg, 1e-6);
  SimSessionOptions bad = level;
  bad.camera_pitch_deg = 31;
  ValidatingSink bad_sink;
  try {
    simulate_session(bad, bad_sink);
    ADD_FAILURE() << "a 31 deg pitch was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "camera_pitch_deg");
  }
}

TEST(SimSessionTruth, AngleTruthCountsTheScriptedRepetitions) {
  SimSessionOptions o = small(false);
  o.motion = "arm_raising";
  o.motion_options.exercise.arm = ExerciseArm::kBoth;
  o.motion_options.exercise.repetitions = 3;
  o.duration_from_motion = true;
  ValidatingSink sink;
  const SimTruth truth = simulate_session(with_session_duration(o), sink);
  const AngleTruth angles = angle_truth(truth);
  ASSERT_EQ(angles.frames.size(), truth.frames.size());
  ASSERT_TRUE(angles.repetitions.has_value());
  EXPECT_EQ(angles.repetitions->summary.count, 3);
  for (const measures::Repetition& r : angles.repetitions->summary.repetitions) {
    if (r.partial) continue;
    EXPECT_NEAR(r.max_deg, 150, 1.0);
    EXPECT_NEAR(r.min_deg, 8, 1.0);
  }
  // The straight arm: elbow flexion near 0, so no humerus axial rotation anywhere.
  for (const measures::JointAngles& a : angles.frames) {
    EXPECT_FALSE(a[static_cast<int>(measures::Angle::kRightHumerusAxialRotation)].defined);
    EXPECT_LT(a[static_cast<int>(measures::Angle::kRightElbowFlexion)].deg, 15);
  }
}

// A trunk tilted right then left, and a forearm rolled into pronation then supination, rest in
// the middle of their motion: three scripted repetitions read three counted ones of the whole
// arc (trunk +-20 deg, forearm +-60 deg), not two cut at the far side.
TEST(SimSessionTruth, AngleTruthCountsRepetitionsThatSwingAboutZero) {
  struct Case {
    const char* motion;
    std::vector<measures::Angle> angles;
    double range_deg;
  };
  for (const Case& c :
       {Case{"torso_tilt", {measures::Angle::kThoraxLateralTilt}, 40},
        Case{"forearm_rolling", {measures::Angle::kLeftPronation, measures::Angle::kRightPronation}, 120}}) {
    SCOPED_TRACE(c.motion);
    SimSessionOptions o = small(false);
    o.motion = c.motion;
    o.motion_options.exercise.repetitions = 3;
    o.duration_from_motion = true;
    ValidatingSink sink;
    const AngleTruth angles = angle_truth(simulate_session(with_session_duration(o), sink));
    ASSERT_TRUE(angles.repetitions.has_value());
    EXPECT_NE(std::find(c.angles.begin(), c.angles.end(), angles.repetitions->angle), c.angles.end())
        << measures::angle_name(angles.repetitions->angle);
    EXPECT_EQ(angles.repetitions->summary.count, 3);
    for (const measures::Repetition& r : angles.repetitions->summary.repetitions) {
      if (r.partial) continue;
      EXPECT_NEAR(r.range_deg, c.range_deg, 0.1 * c.range_deg);
    }
  }
}

TEST(SimSessionTruth, SwappedImuRolesAreSwappedInTheHeaderOnly) {
  SimSessionOptions o = small(false);
  o.duration_s = 1.0;
  o.arm_imu_roles_swapped = true;
  HeaderSink sink;
  const SimTruth truth = simulate_session(o, sink);
  ASSERT_EQ(sink.header.imu_devices_size(), 3);
  EXPECT_EQ(sink.header.imu_devices(0).device_id(), "imu_left");
  EXPECT_EQ(sink.header.imu_devices(0).role(), v1::ImuDevice::ARM_RIGHT);
  EXPECT_EQ(sink.header.imu_devices(1).device_id(), "imu_right");
  EXPECT_EQ(sink.header.imu_devices(1).role(), v1::ImuDevice::ARM_LEFT);
  EXPECT_EQ(sink.header.imu_devices(2).role(), v1::ImuDevice::BASE);
  EXPECT_EQ(truth.devices[0].role, v1::ImuDevice::ARM_LEFT);
  EXPECT_EQ(truth.devices[1].role, v1::ImuDevice::ARM_RIGHT);
}
