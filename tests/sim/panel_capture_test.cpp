// The calibration-panel capture (panel_capture.hpp) run through the frame calibration
// (calib/capture_calibration.hpp): K_from_E and K_from_B come back within what the injected
// noise allows; a panel out of view and a single pose are refused with named errors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "../imu/expect_error.hpp"
#include "sim/panel_capture.hpp"
#include "sim/room_frame.hpp"

using namespace posefuse;
using namespace posefuse::sim;
using posefuse::testing::expect_error;

namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

// A level camera facing the subject, who faces 17 degrees west of north (as sim_session places
// them), and the base IMU mounted on it with a small error.
PanelCaptureRig rig(std::uint64_t seed) {
  PanelCaptureRig r;
  const Quat K_from_Body(Eigen::AngleAxisd(3.14159265358979323846, Vec3::UnitY()));
  r.K_from_W = (K_from_Body * W_from_R(17.2 * kDeg).conjugate()).normalized();
  Mat3 K_from_B_nominal;
  K_from_B_nominal << 0, 1, 0, 0, 0, 1, 1, 0, 0;
  r.K_from_B = (Quat(K_from_B_nominal) * geometry::quat_from_rotation_vector(Vec3(0.01, -0.015, 0.02))).normalized();
  r.seed = seed;
  return r;
}

// What the injected IMU errors allow for one still IMU's orientation: the accelerometer's bias
// and scale/misalignment tilt the measured gravity by at most |b| / g + ||M - I||, and the
// heading built from g x m turns with that tilt by up to 1 / cos(dip) of it (the field dips
// 64 degrees); magnetometer noise averaged over the hold adds sigma / sqrt(n) / H.
double imu_bound_rad(const ImuErrors& e, const ImuSynthOptions& imu, std::size_t samples) {
  const double tilt = e.acc_bias_m_s2.norm() / imu.gravity_m_s2 + (e.acc_scale_misalignment - Mat3::Identity()).norm();
  const double field =
      3.0 * imu.error_model.mag_noise_uT / std::sqrt(static_cast<double>(samples)) / imu.earth_field.horizontal_uT;
  return tilt / std::cos(imu.earth_field.dip_rad) + field;
}

TEST(PanelCapture, CalibrationRecoversKFromEAndKFromBWithinTheInjectedNoise) {
  for (std::uint64_t seed : {3u, 11u}) {
    const PanelCaptureRig r = rig(seed);
    const PanelCaptureResult sim = simulate_panel_capture(PanelCaptureOptions{}, r);
    ASSERT_EQ(sim.capture.poses.size(), 4u);
    const calib::CaptureCalibration result = calib::calibrate_capture(sim.capture);
    const double e_deg = geometry::angle_between(result.mocap.K_from_E, sim.truth.K_from_E) / kDeg;
    const double origin_mm = 1e3 * (result.mocap.E_origin_K - sim.truth.E_origin_K).norm();
    const double b_deg = geometry::angle_between(result.base.K_from_B, sim.truth.K_from_B) / kDeg;
    const double w_deg = geometry::angle_between(result.K_from_W, sim.truth.K_from_W) / kDeg;
    const std::size_t n = sim.capture.poses[0].panel_imu.size();
    // K_from_B per eq. 8 inherits the panel IMU's and the base IMU's orientation errors, the
    // panel IMU's visual misalignment on the panel (truth) and the camera's K_from_P error.
    const double camera_bound_deg = 0.5;
    const double b_bound_deg =
        (imu_bound_rad(sim.truth.panel_imu_errors, r.imu, n) + imu_bound_rad(sim.truth.base_imu_errors, r.imu, n) +
         geometry::angle_between(sim.truth.P_from_panel_imu, Quat::Identity())) /
            kDeg +
        camera_bound_deg;
    std::printf(
        "seed %llu: K_from_E %.3f deg, E origin %.2f mm, markers %.2f px; K_from_B %.3f deg (bound %.2f, "
        "spread %.3f deg), K_from_W %.3f deg\n",
        static_cast<unsigned long long>(seed), e_deg, origin_mm, result.mocap.marker_residual_px, b_deg, b_bound_deg,
        result.base.spread_rad / kDeg, w_deg);
    for (std::size_t i = 0; i < result.poses.size(); ++i) {
      const calib::PanelInCamera& seen = result.poses[i].seen;
      std::printf("  pose %zu: K_from_P %.3f deg, origin %.2f mm, board RMS %.2f mm, markers %.2f px\n", i,
                  geometry::angle_between(seen.pose.X_from_P, sim.truth.K_from_P[i].X_from_P) / kDeg,
                  1e3 * (seen.pose.origin_X - sim.truth.K_from_P[i].origin_X).norm(), 1e3 * seen.board_rms_m,
                  seen.marker_residual_px);
      // Camera per pose: Kinect depth noise (~2-3 mm at 1.3-1.9 m) over strips of hundreds of
      // points gives ~0.1 degree; pixel discretisation of exact renders ~0.05 (tests/calib).
      EXPECT_LT(geometry::angle_between(seen.pose.X_from_P, sim.truth.K_from_P[i].X_from_P), camera_bound_deg * kDeg);
    }
    // Eqs. 4-6: the camera's per-pose error (above) plus the mocap's: 0.3 mm marker noise over a
    // 0.25-0.4 m L turns the Kabsch fit by ~0.3 mm / 0.25 m = 0.07 degree (3 sigma 0.2).
    EXPECT_LT(e_deg, camera_bound_deg + 0.2);
    // Origin: the panel origin's error (~1-2 mm, tests/calib) plus the rotation error times the
    // 2-3 m lever from the panel to E's origin (0.7 deg * 3 m = 37 mm at the bound).
    EXPECT_LT(origin_mm, 2.0 + (camera_bound_deg + 0.2) * kDeg * 3000.0);
    EXPECT_LT(b_deg, b_bound_deg);
    if (seed != 3) continue;
    // Deterministic per seed.
    const PanelCaptureResult again = simulate_panel_capture(PanelCaptureOptions{}, r);
    EXPECT_EQ(again.capture.poses[2].ir, sim.capture.poses[2].ir);
    EXPECT_EQ(again.capture.poses[2].depth_mm, sim.capture.poses[2].depth_mm);
    EXPECT_EQ(again.capture.poses[2].markers_E, sim.capture.poses[2].markers_E);
  }
}

TEST(PanelCapture, WithIdealImusKFromBIsAsGoodAsTheCamera) {
  PanelCaptureRig r = rig(3);
  r.imu.error_model = ImuErrorModel::none();
  PanelCaptureOptions options;
  options.imu_misalignment_deg = 0.0;
  const PanelCaptureResult sim = simulate_panel_capture(options, r);
  const calib::CaptureCalibration result = calib::calibrate_capture(sim.capture);
  const double b_deg = geometry::angle_between(result.base.K_from_B, sim.truth.K_from_B) / kDeg;
  std::printf("ideal IMUs: K_from_B %.3f deg, K_from_W %.3f deg, spread %.3f deg\n", b_deg,
              geometry::angle_between(result.K_from_W, sim.truth.K_from_W) / kDeg, result.base.spread_rad / kDeg);
  EXPECT_LT(b_deg, 0.5);  // the camera's K_from_P error only (eq. 8 with exact W_from_P, W_from_B)
}

TEST(PanelCapture, TheIrImageShowsSaturatedMarkersWithoutDepthOnADullBoard) {
  const PanelCaptureResult sim = simulate_panel_capture(PanelCaptureOptions{}, rig(3));
  const calib::CapturePose& pose = sim.capture.poses[0];
  int saturated = 0, saturated_with_depth = 0;
  for (std::size_t p = 0; p < pose.ir.size(); ++p) {
    if (pose.ir[p] == 65535) {
      ++saturated;
      if (pose.depth_mm[p] != 0) ++saturated_with_depth;
    }
  }
  // Four marker blobs of a 12 mm sphere at 1.3-1.9 m (f = 365 px): 2.3-3.4 px radius, a few
  // tens of pixels each with the partly covered rim.
  EXPECT_GT(saturated, 4 * 10);
  EXPECT_LT(saturated, 4 * 80);
  EXPECT_EQ(saturated_with_depth, 0);
}

TEST(PanelCapture, RefusesAPanelOutOfViewAndTooFewOrTooSimilarPoses) {
  PanelCaptureOptions options;
  const PanelCaptureRig r = rig(5);
  const PanelCaptureResult good = simulate_panel_capture(options, r);
  // One pose only.
  calib::CalibrationCapture one = good.capture;
  one.poses.resize(1);
  expect_error([&] { calib::calibrate_capture(one); }, ErrorCode::kInvalidArgument, "poses", "1 panel pose(s)");
  // The third pose moved 3 m to the side: out of view.
  options.poses_K = good.truth.K_from_P;
  options.poses_K[2].origin_X += Vec3(3.0, 0.0, 0.0);
  const PanelCaptureResult away = simulate_panel_capture(options, r);
  expect_error([&] { calib::calibrate_capture(away.capture); }, ErrorCode::kFailedPrecondition, "poses[2].ir",
               "bright points, expected the panel's 4 markers");
  // Four poses that differ only by a shift: degenerate for eq. 8.
  for (std::size_t i = 0; i < options.poses_K.size(); ++i) {
    options.poses_K[i] = good.truth.K_from_P[0];
    options.poses_K[i].origin_X += Vec3(0.03 * static_cast<double>(i), 0.0, 0.0);
  }
  const PanelCaptureResult same = simulate_panel_capture(options, r);
  expect_error([&] { calib::calibrate_capture(same.capture); }, ErrorCode::kFailedPrecondition, "poses",
               "turned at most");
  options.poses_K.clear();
  options.poses = 0;
  expect_error([&] { simulate_panel_capture(options, r); }, ErrorCode::kInvalidArgument, "panel_capture.poses");
}

}  // namespace
