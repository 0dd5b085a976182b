// Strap detection in RGB + depth (paper 1, II-I) on images rendered in the test.
#include <gtest/gtest.h>

#include "../imu/expect_error.hpp"
#include "forearm/forearm_model.hpp"
#include "forearm/strap_detection.hpp"
#include "geometry/rotation_matrix.hpp"
#include "synthetic_images.hpp"

namespace posefuse::forearm {
namespace {

using namespace posefuse::forearm::testing;
using posefuse::testing::expect_error;

// Where along the core and how far from it the detected strap point lies.
struct StrapError {
  double axial_m, radial_m;
};
StrapError strap_error(const ForearmScene& s, const Vec3& strap_K) {
  const Vec3 axis = (s.wrist_K - s.elbow_K).normalized();
  const double along = (strap_K - s.elbow_K).dot(axis);
  const double radial = (strap_K - s.elbow_K - along * axis).norm();
  return {along - s.strap_to_elbow_m, radial - s.radius_m};
}

TEST(StrapDetection, FindsTheBandOnExactImages) {
  const StrapCameras cameras = test_cameras();
  const ForearmScene scene;
  const ForearmImages images = render_forearm(scene, cameras);
  const StrapDetection d =
      detect_strap(images.gray_view(cameras), images.depth_view(cameras), cameras, scene.elbow_K, scene.wrist_K);
  ASSERT_TRUE(d.found()) << strap_miss_name(d.miss);
  const StrapError e = strap_error(scene, d.strap_K);
  // One colour pixel is 3.8 mm at 2 m; the band centre is found to about half a pixel and the
  // depth pixels matched within 1.5 colour pixels of it straddle the surface by as much.
  EXPECT_LT(std::abs(e.axial_m), 0.004);
  EXPECT_LT(std::abs(e.radial_m), 0.003);
  EXPECT_GT(d.contrast, 100.0);
  EXPECT_GE(d.depth_samples, 1);

  // eq. 10 from the detected strap: the IMU sits at r along F's x from the strap's projection.
  const Vec3 y = (scene.wrist_K - scene.elbow_K).normalized();
  const Vec3 x = (Vec3(0, 0, 1) - Vec3(0, 0, 1).dot(y) * y).normalized();
  geometry::Mat3 R;
  R << x, y, x.cross(y);
  const Quat K_from_F(R);
  const Vec3 imu = imu_position_from_strap(d.strap_K, scene.elbow_K, scene.wrist_K, K_from_F, scene.radius_m);
  const Vec3 truth = scene.elbow_K + scene.strap_to_elbow_m * y + scene.radius_m * x;
  EXPECT_LT((imu - truth).norm(), 0.004);
}

TEST(StrapDetection, NoisyImages) {
  const StrapCameras cameras = test_cameras();
  ForearmScene scene;
  scene.elbow_K = Vec3(-0.2, 0.0, 1.8);  // forearm across the image, pointing a bit away
  scene.wrist_K = Vec3(0.05, 0.05, 1.9);
  scene.strap_to_elbow_m = 0.21;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    // Grey noise 10 levels, depth noise 3 mm (Kinect-like at 2 m).
    const ForearmImages images = render_forearm(scene, cameras, 10.0, 0.003, seed);
    const StrapDetection d =
        detect_strap(images.gray_view(cameras), images.depth_view(cameras), cameras, scene.elbow_K, scene.wrist_K);
    ASSERT_TRUE(d.found()) << strap_miss_name(d.miss);
    const StrapError e = strap_error(scene, d.strap_K);
    EXPECT_LT(std::abs(e.axial_m), 0.008) << "seed " << seed;
    // Mean of a few depth samples with 3 mm noise each.
    EXPECT_LT(std::abs(e.radial_m), 0.006) << "seed " << seed;
  }
}

TEST(StrapDetection, StrapNeverSeen) {
  const StrapCameras cameras = test_cameras();
  ForearmScene scene;
  scene.strap_visible = false;
  const ForearmImages images = render_forearm(scene, cameras, 10.0, 0.003);
  const StrapDetection d =
      detect_strap(images.gray_view(cameras), images.depth_view(cameras), cameras, scene.elbow_K, scene.wrist_K);
  EXPECT_EQ(d.miss, StrapMiss::kNoDarkBand);
  EXPECT_FALSE(d.found());
  EXPECT_LT(d.contrast, 40.0);
}

TEST(StrapDetection, SegmentOutsideOrNoDepth) {
  const StrapCameras cameras = test_cameras();
  const ForearmScene scene;
  ForearmImages images = render_forearm(scene, cameras);
  const StrapDetection outside =
      detect_strap(images.gray_view(cameras), images.depth_view(cameras), cameras, Vec3(3.0, 0.0, 2.0), scene.wrist_K);
  EXPECT_EQ(outside.miss, StrapMiss::kOutsideImage);
  const StrapDetection behind =
      detect_strap(images.gray_view(cameras), images.depth_view(cameras), cameras, Vec3(0.0, 0.0, -1.0), scene.wrist_K);
  EXPECT_EQ(behind.miss, StrapMiss::kOutsideImage);
  std::fill(images.depth_mm.begin(), images.depth_mm.end(), std::uint16_t{0});  // no depth at all
  const StrapDetection hole =
      detect_strap(images.gray_view(cameras), images.depth_view(cameras), cameras, scene.elbow_K, scene.wrist_K);
  EXPECT_EQ(hole.miss, StrapMiss::kNoDepth);
}

TEST(StrapDetection, ReadsOnlyTheProfileRectangle) {
  // The colour image with every pixel outside strap_profile_rect set to 0 (as a colour frame
  // decoded over that rectangle alone may leave them) gives the whole image's result, bit for bit.
  const StrapCameras cameras = test_cameras();
  ForearmScene across;
  across.elbow_K = Vec3(-0.2, 0.0, 1.8);
  across.wrist_K = Vec3(0.05, 0.05, 1.9);
  across.strap_to_elbow_m = 0.21;
  ForearmScene unseen;
  unseen.strap_visible = false;
  for (const ForearmScene& scene : {ForearmScene{}, across, unseen}) {
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      const ForearmImages images = render_forearm(scene, cameras, 10.0, 0.003, seed);
      const geometry::PixelRect rect = strap_profile_rect(cameras, scene.elbow_K, scene.wrist_K);
      ASSERT_FALSE(rect.empty());
      // A forearm's rectangle, not the image.
      EXPECT_LT((rect.col1 - rect.col0 + 1) * (rect.row1 - rect.row0 + 1),
                cameras.color.width * cameras.color.height / 4);
      std::vector<std::uint8_t> only_rect(images.gray.size(), 0);
      for (int row = rect.row0; row <= rect.row1; ++row)
        for (int col = rect.col0; col <= rect.col1; ++col) {
          const std::size_t i = static_cast<std::size_t>(row) * cameras.color.width + col;
          only_rect[i] = images.gray[i];
        }
      const StrapDetection whole =
          detect_strap(images.gray_view(cameras), images.depth_view(cameras), cameras, scene.elbow_K, scene.wrist_K);
      const StrapDetection part = detect_strap({cameras.color.width, cameras.color.height, only_rect.data()},
                                               images.depth_view(cameras), cameras, scene.elbow_K, scene.wrist_K);
      EXPECT_EQ(part.miss, whole.miss);
      EXPECT_EQ(part.fraction, whole.fraction);
      EXPECT_EQ(part.contrast, whole.contrast);
      EXPECT_EQ(part.side_contrast, whole.side_contrast);
      EXPECT_EQ(part.strap_K, whole.strap_K);
    }
  }
  // Where detect_strap finds the forearm outside the image there is nothing to decode.
  EXPECT_TRUE(strap_profile_rect(cameras, Vec3(3.0, 0.0, 2.0), ForearmScene{}.wrist_K).empty());
  EXPECT_TRUE(strap_profile_rect(cameras, Vec3(0.0, 0.0, -1.0), ForearmScene{}.wrist_K).empty());
}

TEST(StrapDetection, RefusesBadInput) {
  const StrapCameras cameras = test_cameras();
  const ForearmScene scene;
  const ForearmImages images = render_forearm(scene, cameras);
  GrayImageView small = images.gray_view(cameras);
  small.width = 100;
  expect_error([&] { detect_strap(small, images.depth_view(cameras), cameras, scene.elbow_K, scene.wrist_K); },
               ErrorCode::kInvalidArgument, "color.pixels");
  DepthImageView no_depth{cameras.depth.width, cameras.depth.height, nullptr};
  expect_error([&] { detect_strap(images.gray_view(cameras), no_depth, cameras, scene.elbow_K, scene.wrist_K); },
               ErrorCode::kInvalidArgument, "depth.pixels");
  expect_error(
      [&] {
        detect_strap(images.gray_view(cameras), images.depth_view(cameras), cameras, Vec3::Constant(NAN),
                     scene.wrist_K);
      },
      ErrorCode::kInvalidArgument, "elbow_K");
  StrapDetectionOptions options;
  options.window_fraction = 0.0;
  expect_error(
      [&] {
        detect_strap(images.gray_view(cameras), images.depth_view(cameras), cameras, scene.elbow_K, scene.wrist_K,
                     options);
      },
      ErrorCode::kInvalidArgument, "options");
  StrapCameras bad = cameras;
  bad.color.fx = 0.0;
  expect_error(
      [&] { detect_strap(images.gray_view(cameras), images.depth_view(cameras), bad, scene.elbow_K, scene.wrist_K); },
      ErrorCode::kInvalidArgument, "cameras.color.fx");
}

}  // namespace
}  // namespace posefuse::forearm
