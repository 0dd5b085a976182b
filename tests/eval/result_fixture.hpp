#pragma once
// Small result directories written in code through session::ResultFiles (the writer the client
// and the simulator's gt/ use), for the reader and score tests.
#include <cmath>
#include <filesystem>
#include <string>

#include "../scratch_dir.hpp"
#include "geometry/quaternion.hpp"
#include "session/result_files.hpp"
#include "session/stages/proto_values.hpp"

namespace posefuse::result_fixture {

inline std::filesystem::path fresh_result_dir(const std::string& name) {
  return posefuse::testing::fresh_scratch_dir("posefuse_result_fixture", name);
}

// What one fixture directory holds; every stream is a simple function of time plus the
// offsets given, so the errors between two such directories are known exactly.
struct FixtureSpec {
  std::int64_t t0_us = 0;                 // added to every camera-clock time
  std::int64_t device_t0_us = 5'000'000;  // first device-clock time of imu_orientations
  double forearm_angle_rad = 0.0;         // K_from_F turned by this about x_F
  double position_offset_m = 0.0;         // IMU positions and joints moved along +z_K
  double r_m = 0.035;
  double K_from_W_angle_rad = 0.0;  // about z
  bool level_camera = false;        // K_from_W also turns W's z (up) onto K's y, as a level camera
  std::int64_t clock_offset_us = -1'000'000;
  double buzzer_tone_hz = 2700.0;
  bool with_joints = true;
  bool with_segment = true;
  v1::Source source = v1::GROUND_TRUTH;
  int frames = 10;                // camera frames at 30 Hz; forearm samples at 80 Hz over the same span
  double angle_offset_deg = 0.0;  // added to every joint angle and repetition range
  bool right_pronation_defined = true;
  bool with_repetitions = true;              // two counted repetitions of right_elbow_flexion (the second's range
                                             // at confidence 0.3) and a partial one
  double uncertain_cut_ambiguity_deg = 0.0;  // the second repetition's cut_ambiguity_deg
  v1::JointAngleKind repetition_angle = v1::RIGHT_ELBOW_FLEXION;
};

// Joint angle a at time t (deg): distinct per angle, changing over time.
inline double fixture_angle_deg(int a, double t_s) { return 10.0 * a + 30.0 * t_s; }

inline geometry::Quat fixture_K_from_F(double t_s) {
  return geometry::quat_from_rotation_vector(geometry::Vec3(0.3 * t_s, 0.1, -0.2));
}

inline double fixture_fit_energy(double t_s) { return 20.0 + 100.0 * t_s; }

inline geometry::Quat fixture_K_from_joint(int joint, double t_s) {
  return geometry::quat_from_rotation_vector(geometry::Vec3(0.01 * joint, 0.2 * t_s, -0.1));
}
inline geometry::Vec3 fixture_imu_K(double t_s) { return {0.1 * t_s, 0.2, 2.0 - 0.05 * t_s}; }

inline void write_fixture(const std::filesystem::path& dir, const FixtureSpec& spec) {
  using session::to_proto;
  session::ResultFiles files(dir);
  const geometry::Quat turn = geometry::quat_from_rotation_vector(geometry::Vec3(spec.forearm_angle_rad, 0, 0));
  const geometry::Vec3 shift(0, 0, spec.position_offset_m);
  const double span_s = static_cast<double>(spec.frames) / 30.0;
  {  // IMU orientations (device clock) and forearm orientations (camera clock) at 80 Hz
    v1::ImuOrientationBatch orientations;
    orientations.set_device_id("imu_right");
    v1::ForearmOrientationBatch forearm;
    forearm.set_device_id("imu_right");
    for (int i = 0; i * 0.0125 < span_s; ++i) {
      const double t = i * 0.0125;
      const auto dt_us = static_cast<std::int64_t>(t * 1e6);
      orientations.add_t_us(spec.device_t0_us + dt_us);
      for (const double c : geometry::to_wxyz(fixture_K_from_F(t) * turn)) orientations.add_w_from_a(c);
      orientations.add_uncertainty_rad(0.04);
      orientations.add_confidence(0.95);
      forearm.add_t_us(spec.t0_us + dt_us);
      for (const double c : geometry::to_wxyz(fixture_K_from_F(t) * turn)) forearm.add_k_from_f(c);
      forearm.add_pronation_rad(0.1);
      forearm.add_uncertainty_rad(0.05);
      forearm.add_confidence(0.9);
    }
    files.write_orientations(orientations);
    files.write_forearm_orientations(forearm);
  }
  for (int f = 0; f < spec.frames; ++f) {
    const double t = f / 30.0;
    v1::FrameResult frame;
    frame.set_t_us(spec.t0_us + static_cast<std::int64_t>(t * 1e6));
    if (spec.with_joints) {
      for (int j = 0; j < 25; ++j) {
        v1::JointEstimate& joint = *frame.add_camera_joints();
        *joint.mutable_position_m() = to_proto(geometry::Vec3(0.01 * j, 0.1 * t, 2.0) + shift);
        joint.set_source(spec.source);
        joint.set_confidence(1.0);
      }
      for (int j = 0; j < 24; ++j) *frame.add_smpl_joint_rotations() = to_proto(fixture_K_from_joint(j, t));
      frame.set_fit_energy(fixture_fit_energy(t));
    }
    v1::ForearmOrientation& forearm = *frame.add_forearms();
    forearm.set_arm(v1::RIGHT);
    *forearm.mutable_k_from_f() = to_proto(fixture_K_from_F(t) * turn);
    forearm.set_source(spec.source);
    v1::ImuPosition& position = *frame.add_imu_positions();
    position.set_device_id("imu_right");
    *position.mutable_position_m() = to_proto(fixture_imu_K(t) + shift);
    position.set_source(f < spec.frames / 2 ? v1::VISUAL : v1::PREDICTED);
    files.write_frame(frame);
  }
  for (int f = 0; f < spec.frames; ++f) {
    const double t = f / 30.0;
    v1::FrameAngles angles;
    angles.set_t_us(spec.t0_us + static_cast<std::int64_t>(t * 1e6));
    for (int a = 0; a < 15; ++a) {
      v1::JointAngle& angle = *angles.add_angles();
      angle.set_kind(static_cast<v1::JointAngleKind>(a + 1));
      angle.set_defined(a != 13 || spec.right_pronation_defined);  // 13: right_pronation
      angle.set_deg(fixture_angle_deg(a, t) + spec.angle_offset_deg);
      angle.set_confidence(a == 3 ? 0.0 : 1.0);  // 3: left_plane_of_elevation, held
      angle.set_held(a == 3);
      angle.set_source(spec.source);
    }
    files.write_angles(angles);
  }
  if (spec.with_repetitions) {
    v1::RepetitionSummary summary;
    summary.set_angle(spec.repetition_angle);
    summary.set_angle_detected(true);
    for (int r = 0; r < 3; ++r) {
      v1::Repetition& rep = *summary.add_repetitions();
      rep.set_t_start_us(spec.t0_us + r * 2'000'000);
      rep.set_t_peak_us(spec.t0_us + r * 2'000'000 + 1'000'000);
      rep.set_t_end_us(spec.t0_us + (r + 1) * 2'000'000);
      rep.set_min_deg(20);
      rep.set_max_deg(60 + 10 * r + spec.angle_offset_deg);
      rep.set_range_deg(40 + 10 * r + spec.angle_offset_deg);
      rep.set_duration_s(2.0);
      rep.set_partial(r == 2);
      rep.set_confidence(r == 1 ? 0.3 : 0.9);  // the second counted one's range is not confident
      if (r == 1) rep.set_cut_ambiguity_deg(spec.uncertain_cut_ambiguity_deg);
    }
    summary.set_count(2);
    files.write_repetitions(summary);
  }
  if (spec.with_segment) {  // frames 5..9 recovered, samples every 12.5 ms
    v1::RecoveredSegment segment;
    segment.set_device_id("imu_right");
    segment.set_method(v1::RecoveredSegment::SMOOTHER);
    segment.set_t_start_us(spec.t0_us + static_cast<std::int64_t>(5 / 30.0 * 1e6));
    segment.set_t_end_us(spec.t0_us + static_cast<std::int64_t>(9 / 30.0 * 1e6));
    for (double t = 5 / 30.0; t < 9 / 30.0 + 0.0125; t += 0.0125) {
      v1::RecoveredSegment::Sample& s = *segment.add_samples();
      s.set_t_us(std::min(segment.t_end_us(), spec.t0_us + static_cast<std::int64_t>(t * 1e6)));
      *s.mutable_imu_m() = to_proto(fixture_imu_K(std::min(t, 9 / 30.0)) + shift);
      *s.mutable_k_from_f() = to_proto(fixture_K_from_F(t));
    }
    files.write_segment(segment);
  }
  v1::CalibrationReport report;
  v1::ForearmModel& model = *report.add_forearms();
  model.set_arm(v1::RIGHT);
  model.set_device_id("imu_right");
  model.set_r_m(spec.r_m);
  model.set_d_se_m(0.15);
  model.set_d_sw_m(0.10);
  model.set_d_ul_m(0.28);
  *model.mutable_a_from_f() = to_proto(geometry::Quat::Identity());
  const geometry::Quat level =
      geometry::quat_from_rotation_vector(geometry::Vec3(spec.level_camera ? -M_PI / 2 : 0, 0, 0));
  *report.mutable_k_from_w() =
      to_proto(level * geometry::quat_from_rotation_vector(geometry::Vec3(0, 0, spec.K_from_W_angle_rad)));
  (*report.mutable_clock_offset_us())["imu_right"] = spec.clock_offset_us;
  report.set_buzzer_tone_hz(spec.buzzer_tone_hz);
  files.write_calibration(report);
  files.close();
}

}  // namespace posefuse::result_fixture
