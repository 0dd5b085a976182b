#include "geometry/pixel_rays.hpp"

#include <gtest/gtest.h>

#include "common/error.hpp"

namespace posefuse::geometry {
namespace {

// The table must give back_project's numbers bit for bit at every pixel and depth, so that the
// forearm stage's points do not change with it.
void expect_table_matches_back_project(const PinholeCamera& camera) {
  const PixelRays rays(camera);
  for (int row = 0; row < camera.height; ++row) {
    for (int col = 0; col < camera.width; ++col) {
      for (const double z : {0.5, 2.137, 7.9}) {
        const Vec3 expected = back_project(camera, col, row, z);
        const Vec3 p = rays.point(col, row, z);
        ASSERT_EQ(p, expected) << "pixel " << col << "," << row << " z " << z;
      }
    }
  }
}

TEST(PixelRays, MatchesBackProjectOnTheDefaultKinectDepthCamera) { expect_table_matches_back_project(PinholeCamera{}); }

TEST(PixelRays, MatchesBackProjectOnAStronglyDistortedCamera) {
  // Barrel distortion of a wide lens (the corner's ray a third steeper than its pixel) and tangential terms.
  const PinholeCamera camera{640, 480, 400.0, 410.0, 330.0, 235.0, -0.25, 0.08, -0.01, 0.003, -0.002};
  const Vec2 corner = *project(camera, back_project(camera, 0.0, 0.0, 1.0));
  ASSERT_NEAR(corner.x(), 0.0, 1e-6);  // back_project is exact there too: the comparison means something
  expect_table_matches_back_project(camera);
}

TEST(PixelRays, BadCameraNamesTheField) {
  const auto field_of = [](const PinholeCamera& camera) {
    try {
      PixelRays rays(camera, "header.depth_intrinsics");
    } catch (const Error& e) {
      return e.field();
    }
    return std::string("no error");
  };
  PinholeCamera empty;
  empty.width = 0;
  EXPECT_EQ(field_of(empty), "header.depth_intrinsics.width");
  PinholeCamera huge;
  huge.width = 100000;
  huge.height = 100000;
  EXPECT_EQ(field_of(huge), "header.depth_intrinsics.width");
  PinholeCamera no_focal;
  no_focal.fx = 0.0;
  EXPECT_EQ(field_of(no_focal), "header.depth_intrinsics.fx");
}

}  // namespace
}  // namespace posefuse::geometry
