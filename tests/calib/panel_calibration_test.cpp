// Frame calibration (paper 1, II-F): the panel rendered at known poses, recovered from IR + depth
// and from mocap markers; eqs. 4-8; refusals of bad geometry.
#include <gtest/gtest.h>

#include <numbers>

#include "../imu/expect_error.hpp"
#include "calib/frame_alignment.hpp"
#include "panel_render.hpp"

namespace posefuse::calib {
namespace {

using posefuse::testing::expect_error;
using testing::kinect_depth_camera;
using testing::PanelRenderOptions;
using testing::render_panel;
constexpr double kDeg = std::numbers::pi / 180.0;

Quat rot(const Vec3& rotation_vector) { return geometry::quat_from_rotation_vector(rotation_vector); }

// The panel 1.6 m in front of the camera, facing it (z_P towards the camera, i.e. -z_K), turned
// and tilted by a few tens of degrees.
PanelPose panel_in_K(const Vec3& tilt = Vec3(0.3, -0.4, 0.2)) {
  // Facing the camera: x_P = -x_K (the image's right... as seen), y_P = +y_K, z_P = -z_K.
  const Quat facing(Eigen::AngleAxisd(std::numbers::pi, Vec3::UnitY()));
  return {rot(tilt) * facing, Vec3(0.15, -0.1, 1.6)};
}

TEST(PanelInCamera, RecoversAnExactPanel) {
  const PanelGeometry panel;
  const PinholeCamera camera = kinect_depth_camera();
  for (const Vec3& tilt : {Vec3(0.3, -0.4, 0.2), Vec3(-0.2, 0.5, -0.6), Vec3(0.0, 0.0, 1.2)}) {
    const PanelPose truth = panel_in_K(tilt);
    const auto images = render_panel(panel, truth, camera);
    const PanelInCamera seen = panel_in_camera(images.ir_view(camera), images.depth_view(camera), camera, panel);
    // Pixel discretisation only: the strips' PCA over ~1000 points, the markers' centroids.
    EXPECT_LT(geometry::angle_between(seen.pose.X_from_P, truth.X_from_P), 0.1 * kDeg) << tilt.transpose();
    EXPECT_LT((seen.pose.origin_X - truth.origin_X).norm(), 0.001) << tilt.transpose();
    EXPECT_LT(seen.board_rms_m, 0.001);
    EXPECT_LT(seen.marker_residual_px, 0.3);
    EXPECT_LT(seen.intersection_gap_m, 0.001);
    std::printf("exact panel tilt %s: %.3f deg, %.2f mm, markers %.2f px, x/y/board points %d/%d/%d\n",
                std::to_string(tilt.norm()).c_str(), geometry::angle_between(seen.pose.X_from_P, truth.X_from_P) / kDeg,
                1e3 * (seen.pose.origin_X - truth.origin_X).norm(), seen.marker_residual_px, seen.x_points,
                seen.y_points, seen.board_points);
  }
}

TEST(PanelInCamera, RecoversANoisyPanel) {
  const PanelGeometry panel;
  const PinholeCamera camera = kinect_depth_camera();
  const PanelPose truth = panel_in_K();
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    PanelRenderOptions o;
    o.depth_noise_m = 0.003;  // Kinect v2 at 1.6 m
    o.ir_noise = 400.0;
    o.seed = seed;
    const auto images = render_panel(panel, truth, camera, o);
    const PanelInCamera seen = panel_in_camera(images.ir_view(camera), images.depth_view(camera), camera, panel);
    EXPECT_LT(geometry::angle_between(seen.pose.X_from_P, truth.X_from_P), 0.4 * kDeg);
    EXPECT_LT((seen.pose.origin_X - truth.origin_X).norm(), 0.002);
    EXPECT_NEAR(seen.board_rms_m, 0.003, 0.0008);  // the depth noise itself
    std::printf("noisy panel seed %d: %.3f deg, %.2f mm, board RMS %.2f mm, markers %.2f px\n", static_cast<int>(seed),
                geometry::angle_between(seen.pose.X_from_P, truth.X_from_P) / kDeg,
                1e3 * (seen.pose.origin_X - truth.origin_X).norm(), 1e3 * seen.board_rms_m, seen.marker_residual_px);
  }
}

TEST(PanelInCamera, RefusesBadGeometry) {
  const PanelGeometry panel;
  const PinholeCamera camera = kinect_depth_camera();
  PanelRenderOptions covered;
  covered.cover_marker_3 = true;
  auto images = render_panel(panel, panel_in_K(), camera, covered);
  expect_error([&] { panel_in_camera(images.ir_view(camera), images.depth_view(camera), camera, panel); },
               ErrorCode::kFailedPrecondition, "ir", "found 3 bright points");
  PanelRenderOptions stepped;  // half the board 2.5 cm proud of the rest (6 mm RMS from the best plane)
  stepped.step_m = 0.025;
  images = render_panel(panel, panel_in_K(), camera, stepped);
  expect_error([&] { panel_in_camera(images.ir_view(camera), images.depth_view(camera), camera, panel); },
               ErrorCode::kFailedPrecondition, "depth.board", "not flat");
  // Nearly edge-on: the strips shrink to a few pixels across.
  images = render_panel(panel, panel_in_K(Vec3(0.0, 1.45, 0.0)), camera);
  try {
    panel_in_camera(images.ir_view(camera), images.depth_view(camera), camera, panel);
    ADD_FAILURE() << "an edge-on panel was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kFailedPrecondition) << e.what();
  }
  images = render_panel(panel, panel_in_K(), camera);
  IrImageView small = images.ir_view(camera);
  small.width = 100;
  expect_error([&] { panel_in_camera(small, images.depth_view(camera), camera, panel); }, ErrorCode::kInvalidArgument,
               "ir.pixels");
}

TEST(MocapToCamera, Eqs4To6FromOneAndSeveralPoses) {
  const PanelGeometry panel;
  const PinholeCamera camera = kinect_depth_camera();
  // The mocap frame E placed in K (what eqs. 4-6 must find).
  const Quat K_from_E = rot(Vec3(-1.2, 0.4, 0.3));
  const Vec3 E_origin_K(-0.8, -1.1, 3.0);
  std::vector<std::array<Vec3, 4>> markers;
  std::vector<PanelInCamera> seen;
  for (const Vec3& tilt : {Vec3(0.3, -0.4, 0.2), Vec3(-0.2, 0.5, -0.6)}) {
    const PanelPose truth = panel_in_K(tilt);
    std::array<Vec3, 4> m{};
    for (std::size_t i = 0; i < 4; ++i) {
      m[i] = K_from_E.conjugate() * (truth.to_X(panel.markers_P()[i]) - E_origin_K);  // what the mocap measures
    }
    markers.push_back(m);
    const auto images = render_panel(panel, truth, camera);
    seen.push_back(panel_in_camera(images.ir_view(camera), images.depth_view(camera), camera, panel));
    const MocapToCamera one = mocap_to_camera(m, seen.back(), camera, panel);
    EXPECT_LT(geometry::angle_between(one.K_from_E, K_from_E), 0.1 * kDeg);
    // A point 1 m from the panel maps within the rotation error times 1 m plus the origin error.
    const Vec3 p_E(0.5, 1.0, 0.2);
    EXPECT_LT((one.to_K(p_E) - (E_origin_K + K_from_E * p_E)).norm(), 0.003);
    EXPECT_LT(one.marker_residual_px, 0.3);
  }
  const MocapToCamera both = mocap_to_camera(markers, seen, camera, panel);
  EXPECT_EQ(both.poses, 2);
  EXPECT_LT(geometry::angle_between(both.K_from_E, K_from_E), 0.1 * kDeg);
  EXPECT_LT((both.E_origin_K - E_origin_K).norm(), 0.003);
  std::printf("mocap->camera from 2 poses: %.3f deg, origin %.2f mm, markers %.2f px\n",
              geometry::angle_between(both.K_from_E, K_from_E) / kDeg, 1e3 * (both.E_origin_K - E_origin_K).norm(),
              both.marker_residual_px);

  // Mislabelled mocap markers (M1 and M2 swapped) do not fit the L.
  std::array<Vec3, 4> swapped = markers[0];
  std::swap(swapped[1], swapped[2]);
  expect_error([&] { mocap_to_camera(swapped, seen[0], camera, panel); }, ErrorCode::kFailedPrecondition, "markers_E");
  // A panel that moved between the readings of the two systems.
  std::vector<std::array<Vec3, 4>> moved = markers;
  for (Vec3& m : moved[1]) m += Vec3(0.05, 0, 0);
  expect_error([&] { mocap_to_camera(moved, seen, camera, panel); }, ErrorCode::kFailedPrecondition, "mocap.poses");
  expect_error(
      [&] { mocap_to_camera(std::vector<std::array<Vec3, 4>>{}, std::vector<PanelInCamera>{}, camera, panel); },
      ErrorCode::kInvalidArgument, "poses");
  std::array<Vec3, 4> collinear{Vec3(0, 0, 0), Vec3(0.1, 0, 0), Vec3(0.2, 0, 0), Vec3(0.3, 0, 0)};
  expect_error([&] { panel_pose_from_markers(collinear, panel); }, ErrorCode::kInvalidArgument, "markers_E");
}

TEST(BaseImuInCamera, Eqs7And8) {
  const Quat K_from_B = rot(Vec3(0.1, 2.0, -0.2));
  const Quat K_from_W = rot(Vec3(-1.4, 0.2, 0.5));
  std::vector<PanelImuReading> readings;
  for (const Vec3& tilt : {Vec3(0.3, -0.4, 0.2), Vec3(-0.2, 0.5, -0.6), Vec3(0.1, 0.1, 1.0)}) {
    PanelImuReading r;
    r.K_from_P = panel_in_K(tilt).X_from_P;
    r.W_from_P = K_from_W.conjugate() * r.K_from_P;
    r.W_from_B = K_from_W.conjugate() * K_from_B;
    readings.push_back(r);
  }
  const BaseImuAlignment exact = base_imu_in_camera(readings);
  EXPECT_LT(geometry::angle_between(exact.K_from_B, K_from_B), 1e-7);
  EXPECT_LT(geometry::angle_between(K_from_W_from_base(exact.K_from_B, readings[0].W_from_B), K_from_W), 1e-7);
  // 1 degree of panel-IMU error per reading averages down; 10 degrees on one is refused.
  readings[0].W_from_P = readings[0].W_from_P * rot(Vec3(0.0, 0.0, 1.0 * kDeg));
  EXPECT_LT(geometry::angle_between(base_imu_in_camera(readings).K_from_B, K_from_B), 0.5 * kDeg);
  readings[1].W_from_P = readings[1].W_from_P * rot(Vec3(10.0 * kDeg, 0.0, 0.0));
  expect_error([&] { base_imu_in_camera(readings); }, ErrorCode::kFailedPrecondition, "readings", "spread");
  readings[2].W_from_B = Quat(0, 0, 0, 0);
  expect_error([&] { base_imu_in_camera(readings); }, ErrorCode::kInvalidArgument, "readings[2].W_from_B");
  expect_error([&] { base_imu_in_camera({}); }, ErrorCode::kInvalidArgument, "readings");
}

}  // namespace
}  // namespace posefuse::calib
