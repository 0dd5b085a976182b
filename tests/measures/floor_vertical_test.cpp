// The vertical from the floor of a depth frame: a room rendered analytically (floor, back wall,
// a box standing for the person in the body index) seen by a camera tilted and rolled, with
// Kinect v2-like depth noise; the floor's normal is the vertical to a fraction of a degree, a bent
// floor says it is less sure, and a frame without a floor gives none.
#include "measures/floor_vertical.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "common/error.hpp"
#include "floor_scene.hpp"

namespace posefuse::measures {
namespace {

using geometry::Vec3;

using testing::Frame;
using testing::kDeg;
using testing::render;
using testing::Room;
using testing::room;

double angle_deg(const Vec3& a, const Vec3& b) { return std::atan2(a.cross(b).norm(), a.dot(b)) / kDeg; }

TEST(FloorVertical, TheFloorsNormalIsTheVerticalOfATiltedCamera) {
  const geometry::PinholeCamera camera;
  for (const auto& [pitch, roll] : {std::pair{0.0, 0.0}, {10.0, 0.0}, {20.0, 5.0}, {-5.0, -8.0}}) {
    SCOPED_TRACE("pitch " + std::to_string(pitch) + ", roll " + std::to_string(roll));
    const Room r = room(pitch, roll);
    const Frame frame = render(camera, r.planes);
    const std::optional<FloorVertical> floor = floor_vertical(frame.depth_mm, frame.body_index, camera);
    ASSERT_TRUE(floor.has_value());
    EXPECT_LT(angle_deg(floor->up_K, r.up_K), 0.3);
    EXPECT_NEAR(floor->camera_height_m, 1.0, 0.01);
    EXPECT_GT(floor->points, 200);
    // The spread is what the floor itself says: noise alone keeps it small, but not zero.
    EXPECT_GT(floor->spread_rad, 0.0);
    EXPECT_LT(floor->spread_rad, 0.5 * kDeg);
  }
}

// A floor whose far part rises by 4 degrees: the vertical is off by a part of that, and its
// spread grows to cover it.
TEST(FloorVertical, ABentFloorSpreadsMore) {
  const geometry::PinholeCamera camera;
  const Room flat = room(10, 0);
  const Frame flat_frame = render(camera, flat.planes);
  const double spread_flat = floor_vertical(flat_frame.depth_mm, flat_frame.body_index, camera)->spread_rad;
  // The far floor: turned up by 4 degrees about K's x through the line 3 m ahead on the floor.
  Room bent = flat;
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(-4 * kDeg, Vec3::UnitX()).toRotationMatrix();
  const Eigen::Matrix3d K_from_level = Eigen::AngleAxisd(-10 * kDeg, Vec3::UnitX()).toRotationMatrix();
  const Vec3 hinge_K = K_from_level * Vec3(0, -1.0, 3.0);
  const Vec3 far_normal = K_from_level * turn * Vec3::UnitY();
  // The near floor ends at the hinge, the far one starts there: a pixel sees the nearer of the
  // two only on its own side, which the minimum of z gives for a floor bent upwards.
  bent.planes.push_back({far_normal, far_normal.dot(hinge_K)});
  const Frame frame = render(camera, bent.planes);
  const std::optional<FloorVertical> floor = floor_vertical(frame.depth_mm, frame.body_index, camera);
  ASSERT_TRUE(floor.has_value());
  const double error_deg = angle_deg(floor->up_K, flat.up_K);
  EXPECT_GT(floor->spread_rad, 3 * spread_flat);
  EXPECT_GT(floor->spread_rad / kDeg, 0.5 * error_deg);
}

TEST(FloorVertical, NoFloorInViewGivesNone) {
  const geometry::PinholeCamera camera;
  // Looking up 40 degrees: the lower edge of the view (30 degrees below the axis) stays above the
  // horizon, so only the wall is seen.
  const Room up = room(-40, 0);
  const Frame wall = render(camera, {up.planes[1]});
  EXPECT_FALSE(floor_vertical(wall.depth_mm, wall.body_index, camera).has_value());
  // Nothing but the person.
  Frame person = render(camera, {});
  EXPECT_FALSE(floor_vertical(person.depth_mm, person.body_index, camera).has_value());
}

TEST(FloorVertical, BadSizesAndOptionsAreNamed) {
  const geometry::PinholeCamera camera;
  const Frame frame = render(camera, room(10, 0).planes);
  const auto field_of = [&](const std::vector<std::uint16_t>& depth, const std::vector<std::uint8_t>& body,
                            const FloorVerticalOptions& options) {
    try {
      floor_vertical(depth, body, camera, options);
    } catch (const Error& e) {
      return e.field();
    }
    return std::string("none");
  };
  EXPECT_EQ(field_of({1, 2}, frame.body_index, {}), "depth_mm");
  EXPECT_EQ(field_of(frame.depth_mm, {}, {}), "body_index");
  FloorVerticalOptions options;
  options.pixel_step = 0;
  EXPECT_EQ(field_of(frame.depth_mm, frame.body_index, options), "floor_vertical_options.pixel_step");
  options = {};
  options.inlier_distance_m = NAN;
  EXPECT_EQ(field_of(frame.depth_mm, frame.body_index, options), "floor_vertical_options.inlier_distance_m");
  options = {};
  options.min_points = 2;
  EXPECT_EQ(field_of(frame.depth_mm, frame.body_index, options), "floor_vertical_options.min_points");
  options = {};
  options.iterations = 0;
  EXPECT_EQ(field_of(frame.depth_mm, frame.body_index, options), "floor_vertical_options.iterations");
}

}  // namespace
}  // namespace posefuse::measures
