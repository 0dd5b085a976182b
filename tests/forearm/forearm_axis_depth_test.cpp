#include "forearm/forearm_axis_depth.hpp"

#include <gtest/gtest.h>

#include "common/error.hpp"
#include "geometry/segment_distance.hpp"
#include "synthetic_images.hpp"

namespace posefuse::forearm {
namespace {

using testing::ForearmScene;
using testing::render_forearm;
using testing::test_cameras;

// Distance of p from the infinite line through a and b.
double distance_to_line(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 d = (b - a).normalized();
  return ((p - a) - (p - a).dot(d) * d).norm();
}

// SDK-like joints: each moved by a few centimetres in different directions.
struct BiasedJoints {
  Vec3 elbow_K, wrist_K;
};
BiasedJoints biased(const ForearmScene& s) {
  return {s.elbow_K + Vec3(0.06, -0.05, 0.04), s.wrist_K + Vec3(-0.05, 0.07, -0.06)};
}

TEST(ForearmAxisDepth, FindsTheTrueAxisFromBiasedJoints) {
  const ForearmScene scene;  // forearm 26 cm long at 2 m, radius 3.5 cm
  const StrapCameras cameras = test_cameras();
  const auto images = render_forearm(scene, cameras);
  const BiasedJoints sdk = biased(scene);
  const auto axis =
      measure_forearm_axis(images.depth_view(cameras), geometry::PixelRays(cameras.depth), sdk.elbow_K, sdk.wrist_K);
  ASSERT_TRUE(axis.has_value());
  const Vec3 true_direction = (scene.wrist_K - scene.elbow_K).normalized();
  const double angle_deg =
      std::acos(std::clamp((axis->wrist_K - axis->elbow_K).normalized().dot(true_direction), -1.0, 1.0)) * 180.0 /
      EIGEN_PI;
  EXPECT_LT(angle_deg, 2.0);
  // A depth pixel is ~11 mm wide at 2 m and depth is in whole millimetres.
  EXPECT_LT(distance_to_line(axis->elbow_K, scene.elbow_K, scene.wrist_K), 0.006);
  EXPECT_LT(distance_to_line(axis->wrist_K, scene.elbow_K, scene.wrist_K), 0.006);
  EXPECT_NEAR((axis->elbow_K - scene.elbow_K).norm(), 0.0, 0.015);
  EXPECT_NEAR((axis->wrist_K - scene.wrist_K).norm(), 0.0, 0.015);
  EXPECT_NEAR(axis->radius_m, scene.radius_m, 0.006);
  // The biased SDK segment itself is far off: the test means something.
  EXPECT_GT(distance_to_line(sdk.elbow_K, scene.elbow_K, scene.wrist_K), 0.05);
}

// The hand continues the forearm's cylinder: the distal end of the seen points is the hand's
// end, 10 cm beyond the wrist. The wrist comes from the width profile, wherever the SDK's wrist
// lies along the arm (5 cm short of the true wrist or 5 cm beyond it, i.e. on the hand).
TEST(ForearmAxisDepth, WristWhereTheHandBeginsWhateverTheSdkWristBias) {
  ForearmScene scene;  // forearm 26 cm long at 2 m, radius 3.5 cm
  scene.hand_length_m = 0.10;
  scene.hand_radius_m = 0.045;
  // A Kinect v2-like depth camera (6 mm pixels at 2 m): the width profile needs the resolution.
  StrapCameras cameras = test_cameras();
  cameras.depth = {512, 424, 366.0, 366.0, 256.0, 212.0, 0.02, -0.05, 0.0, 0.0, 0.0};
  const auto images = render_forearm(scene, cameras, 0.0, 0.001, 3);
  const Vec3 along = (scene.wrist_K - scene.elbow_K).normalized();
  ForearmAxisOptions distal_end;
  distal_end.wrist_from_width = false;
  for (const double bias_m : {-0.05, 0.0, 0.05}) {
    const BiasedJoints sdk = biased(scene);
    const Vec3 sdk_wrist = scene.wrist_K + bias_m * along + Vec3(-0.02, 0.0, 0.03);
    const auto axis =
        measure_forearm_axis(images.depth_view(cameras), geometry::PixelRays(cameras.depth), sdk.elbow_K, sdk_wrist);
    ASSERT_TRUE(axis.has_value()) << bias_m;
    EXPECT_LT(std::abs((axis->wrist_K - scene.wrist_K).dot(along)), 0.015) << bias_m;
    EXPECT_LT(distance_to_line(axis->wrist_K, scene.elbow_K, scene.wrist_K), 0.008) << bias_m;
    // The distal end alone runs on over the hand (the failure this replaces).
    const auto end = measure_forearm_axis(images.depth_view(cameras), geometry::PixelRays(cameras.depth), sdk.elbow_K,
                                          sdk_wrist, distal_end);
    ASSERT_TRUE(end.has_value()) << bias_m;
    EXPECT_GT((end->wrist_K - scene.wrist_K).dot(along), 0.07) << bias_m;
  }
}

TEST(ForearmAxisDepth, DepthNoiseOfTwoMillimetres) {
  ForearmScene scene;
  scene.elbow_K = Vec3(-0.15, 0.1, 1.8);
  scene.wrist_K = Vec3(0.1, 0.0, 1.7);  // a horizontal forearm, tilted towards the camera
  const StrapCameras cameras = test_cameras();
  const auto images = render_forearm(scene, cameras, 0.0, 0.002, 7);
  const BiasedJoints sdk = biased(scene);
  const auto axis =
      measure_forearm_axis(images.depth_view(cameras), geometry::PixelRays(cameras.depth), sdk.elbow_K, sdk.wrist_K);
  ASSERT_TRUE(axis.has_value());
  const Vec3 true_direction = (scene.wrist_K - scene.elbow_K).normalized();
  EXPECT_GT((axis->wrist_K - axis->elbow_K).normalized().dot(true_direction), std::cos(3.0 * EIGEN_PI / 180.0));
  EXPECT_LT(distance_to_line(0.5 * (axis->elbow_K + axis->wrist_K), scene.elbow_K, scene.wrist_K), 0.008);
}

TEST(ForearmAxisDepth, NothingThereGivesNoAxis) {
  ForearmScene scene;
  const StrapCameras cameras = test_cameras();
  const auto images = render_forearm(scene, cameras);
  // Joints 60 cm beside the forearm: only the far wall lies in the search region.
  const Vec3 elbow = scene.elbow_K + Vec3(0.6, 0.0, 0.0), wrist = scene.wrist_K + Vec3(0.6, 0.0, 0.0);
  EXPECT_FALSE(
      measure_forearm_axis(images.depth_view(cameras), geometry::PixelRays(cameras.depth), elbow, wrist).has_value());
}

// The pixel-ray table and the depth cut must keep exactly the points that back-projecting every
// pixel of the window and measuring its distance to the segment keeps, in the same order.
TEST(ForearmAxisDepth, PointsNearSegmentAreThoseOfBackProjectingEachPixel) {
  ForearmScene scene;
  scene.hand_length_m = 0.10;
  scene.hand_radius_m = 0.045;
  StrapCameras cameras = test_cameras();
  cameras.depth = {512, 424, 366.0, 366.0, 256.0, 212.0, 0.09, -0.27, 0.09, 0.001, -0.002};
  const auto images = render_forearm(scene, cameras);
  const DepthImageView depth = images.depth_view(cameras);
  const geometry::PixelRays rays(cameras.depth);
  const BiasedJoints sdk = biased(scene);
  // The segment on the forearm, and 10 cm behind it (the forearm's surface then lies near the
  // search region's front in depth).
  for (const auto& [behind_m, radius_m] : {std::pair{0.0, 0.04}, std::pair{0.0, 0.15}, std::pair{0.1, 0.15}}) {
    const Vec3 a = sdk.elbow_K + Vec3(0, 0, behind_m), b = sdk.wrist_K + Vec3(0, 0, behind_m);
    const std::vector<Vec3> points = depth_points_near_segment(depth, rays, a, b, radius_m);
    std::vector<Vec3> expected;
    for (int row = 0; row < depth.height; ++row) {
      for (int col = 0; col < depth.width; ++col) {
        const std::uint16_t mm = depth.at(col, row);
        if (mm == 0) continue;
        const Vec3 p = geometry::back_project(cameras.depth, col, row, 1e-3 * mm);
        if (geometry::distance_to_segment(p, a, b) <= radius_m) expected.push_back(p);
      }
    }
    ASSERT_GT(expected.size(), 100u);
    ASSERT_EQ(points.size(), expected.size()) << behind_m << " m behind, radius " << radius_m;
    for (std::size_t i = 0; i < points.size(); ++i) EXPECT_EQ(points[i], expected[i]) << i;
  }
}

TEST(ForearmAxisDepth, BadInputNamesTheField) {
  const ForearmScene scene;
  const StrapCameras cameras = test_cameras();
  const auto images = render_forearm(scene, cameras);
  const geometry::PixelRays rays(cameras.depth);
  const auto field_of = [&](const DepthImageView& depth, const Vec3& elbow, const Vec3& wrist) {
    try {
      measure_forearm_axis(depth, rays, elbow, wrist);
    } catch (const Error& e) {
      return e.field();
    }
    return std::string("no error");
  };
  const DepthImageView good = images.depth_view(cameras);
  EXPECT_EQ(field_of({good.width - 1, good.height, good.pixels}, scene.elbow_K, scene.wrist_K), "depth.pixels");
  EXPECT_EQ(field_of(good, Vec3(NAN, 0, 1), scene.wrist_K), "elbow_K");
  EXPECT_EQ(field_of(good, scene.elbow_K, Vec3(0, 0, -1)), "wrist_K");
  EXPECT_EQ(field_of(good, scene.elbow_K, scene.elbow_K), "elbow_K/wrist_K");
}

}  // namespace
}  // namespace posefuse::forearm
