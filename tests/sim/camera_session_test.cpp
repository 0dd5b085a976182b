// Depth, body index and skeleton chunks of a simulated arm-raising session pass SessionValidator.
#include "sim/camera_session.hpp"

#include <gtest/gtest.h>

#include <cstdio>

#include "common/error.hpp"
#include "raycast/mesh_scene.hpp"
#include "session/image_codec.hpp"
#include "session/session_validator.hpp"
#include "test_camera.hpp"

using namespace posefuse;
using namespace posefuse::sim;

namespace {

using enum posefuse::geometry::KinectJoint;

CameraSessionOptions small_session() {
  CameraSessionOptions o;
  o.intrinsics = sim::testing::quarter_kinect_intrinsics();
  o.duration_s = 1.0;
  o.seed = 12;
  o.depth_noise.max_edge_shift_px = 1;  // the SDK's ~2 px at full resolution, at a quarter of it
  return o;
}

}  // namespace

TEST(CameraSession, ArmRaisingChunksValidate) {
  const body::PoseLayout layout = body::PoseLayout::full_body();
  const CameraSessionOptions options = small_session();
  const CameraSessionResult r = simulate_camera_session(options, layout, arm_raising_sequence(layout, 2.0));
  ASSERT_EQ(r.t_us.size(), 31u);
  ASSERT_EQ(r.chunks.size(), 3 * 31u);
  EXPECT_EQ(r.t_us[1], 33333);

  session::SessionValidator validator;
  v1::SessionChunk header;
  header.mutable_header()->CopyFrom(r.header);
  ASSERT_NO_THROW(validator.check(header));
  for (const auto& c : r.chunks) ASSERT_NO_THROW(validator.check(c)) << c.ShortDebugString().substr(0, 200);
  v1::SessionChunk end;
  end.mutable_end()->CopyFrom(validator.counts());
  ASSERT_NO_THROW(validator.check(end));
  EXPECT_NO_THROW(validator.finish());
  EXPECT_EQ(validator.counts().depth_frames(), 31u);
  EXPECT_EQ(validator.counts().skeleton_frames(), 31u);

  // The person, the wall and the floor are all in the depth image; the body index marks the
  // person only.
  const cv::Mat depth = session::decode_depth(r.chunks[0].depth());
  const cv::Mat ids = session::decode_body_index(r.chunks[1].body_index());
  int body = 0, body_near = 0, wall = 0, floor = 0;
  for (int row = 0; row < depth.rows; ++row) {
    for (int col = 0; col < depth.cols; ++col) {
      const int z = depth.at<std::uint16_t>(row, col);
      if (ids.at<std::uint8_t>(row, col) == options.body_id) {
        ++body;
        body_near += std::abs(z - 2500) < 300;  // the rest: dilated edges, flying pixels
      } else if (std::abs(z - 4000) < 50) {
        ++wall;
      } else if (z > 0 && row > depth.rows / 2) {
        ++floor;
      }
    }
  }
  // Every body pixel off the person's depth is within the edge shift of one on it.
  const int shift = options.depth_noise.max_edge_shift_px;
  for (int row = 0; row < depth.rows; ++row) {
    for (int col = 0; col < depth.cols; ++col) {
      if (ids.at<std::uint8_t>(row, col) != options.body_id) continue;
      bool near_person = false;
      for (int r = std::max(0, row - shift - 1); r <= std::min(depth.rows - 1, row + shift + 1); ++r) {
        for (int c = std::max(0, col - shift - 1); c <= std::min(depth.cols - 1, col + shift + 1); ++c) {
          near_person |= std::abs(depth.at<std::uint16_t>(r, c) - 2500) < 300;
        }
      }
      EXPECT_TRUE(near_person) << col << ", " << row;
    }
  }
  std::printf(
      "frame 0: %d body pixels (%d at the person's depth), %d wall pixels, %d other (floor) pixels in the lower half\n",
      body, body_near, wall, floor);
  // At this resolution the 1 px edge shift adds a large share of the thin limbs' pixels, so
  // only the structure above is checked, not a ratio.
  EXPECT_GT(body_near, 300);
  EXPECT_GT(wall, 2000);
  EXPECT_GT(floor, 300);

  // The arms go up at t = 1 s (half the period): the left hand is above the head then.
  const Eigen::Matrix3Xd& start = r.true_camera_joints_K.front();
  const Eigen::Matrix3Xd& middle = r.true_camera_joints_K.back();
  EXPECT_LT(start(1, kHandLeft), start(1, kSpineBase));
  EXPECT_GT(middle(1, kHandLeft), middle(1, kHead));
}

TEST(CameraSession, RejectsBadPoseSequence) {
  const body::PoseLayout layout = body::PoseLayout::full_body();
  EXPECT_THROW(simulate_camera_session(small_session(), layout, [](double) { return Eigen::VectorXd::Zero(3); }),
               Error);
  CameraSessionOptions bad = small_session();
  bad.rate_hz = 0;
  EXPECT_THROW(simulate_camera_session(bad, layout, arm_raising_sequence(layout, 2.0)), Error);
}
