// The frame assembler on the session fixture (every chunk kind, canonical order) and on streams
// changed to be incomplete, duplicated or out of order: what it pairs, what it refuses by name.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <variant>
#include <vector>

#include "fixture.hpp"
#include "geometry/pinhole_camera.hpp"
#include "raycast/depth_camera.hpp"
#include "session/frame_assembler.hpp"
#include "session/image_codec.hpp"
#include "session/stage_inputs.hpp"

namespace posefuse::session {
namespace {

using testing::make_session;

template <class T>
std::vector<T> all_of(const std::vector<SessionInput>& inputs) {
  std::vector<T> out;
  for (const SessionInput& input : inputs) {
    if (const T* value = std::get_if<T>(&input)) out.push_back(*value);
  }
  return out;
}

std::vector<v1::SessionChunk> without(std::vector<v1::SessionChunk> chunks, v1::SessionChunk::ChunkCase kind, int n) {
  chunks.erase(chunks.begin() + static_cast<std::ptrdiff_t>(testing::index_of(chunks, kind, n)));
  testing::recount_end(chunks);
  return chunks;
}

bool warned(const AssembledSession& s, const std::string& code, const std::string& field) {
  for (const AssemblyWarning& w : s.warnings) {
    if (w.code == code && w.field == field) return true;
  }
  return false;
}

TEST(FrameAssembler, PairsEveryCameraStreamOfAnInstantIntoOneFrame) {
  const std::vector<v1::SessionChunk> chunks = make_session();
  const AssembledSession s = assemble_session(chunks);
  const auto frames = all_of<CameraFrame>(s.inputs);
  ASSERT_EQ(frames.size(), 3u);
  for (std::size_t f = 0; f < frames.size(); ++f) {
    const v1::SessionChunk& depth = chunks[testing::index_of(chunks, v1::SessionChunk::kDepth, static_cast<int>(f))];
    EXPECT_EQ(frames[f].t_us, depth.depth().t_us());
    // The depth image is the chunk's, decoded once (by the validator).
    const cv::Mat expected = decode_depth(depth.depth());
    ASSERT_EQ(frames[f].depth_mm.size(), expected.size());
    EXPECT_EQ(cv::countNonZero(frames[f].depth_mm != expected), 0);
    EXPECT_FALSE(frames[f].body_index.empty());
    ASSERT_NE(frames[f].skeleton(0), nullptr);
  }
  // Frame 1 holds both bodies; the colour frames (1 ms after frames 0 and 1) join those frames.
  EXPECT_EQ(frames[1].skeletons.size(), 2u);
  EXPECT_NE(frames[1].skeleton(2), nullptr);
  EXPECT_EQ(frames[0].color_t_us, frames[0].t_us + 1000);
  EXPECT_FALSE(frames[0].color.empty());
  EXPECT_FALSE(frames[1].color.empty());
  EXPECT_TRUE(frames[2].color.empty());
  EXPECT_TRUE(s.warnings.empty());
  // IMU batches, audio chunks and the sync events that a stage reads (not OTHER).
  std::size_t imu_samples = 0;
  for (const ImuBlock& b : all_of<ImuBlock>(s.inputs)) imu_samples += b.samples.size();
  EXPECT_EQ(imu_samples, 3u * 70u);
  EXPECT_EQ(all_of<AudioBlock>(s.inputs).size(), 3u);
  const auto events = all_of<ClockEvent>(s.inputs);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].kind, ClockEvent::Kind::kBuzzerStop);
  EXPECT_EQ(events[1].kind, ClockEvent::Kind::kBleReceipt);
  EXPECT_EQ(events[1].ble_sequence, 0x0201u);
}

TEST(FrameAssembler, SkeletonJointsKeepPositionsStatesAndOrientations) {
  const std::vector<v1::SessionChunk> chunks = make_session();
  const v1::SkeletonFrame& proto = chunks[testing::index_of(chunks, v1::SessionChunk::kSkeleton)].skeleton();
  const CameraFrame frame = all_of<CameraFrame>(assemble_session(chunks).inputs).front();
  const Skeleton& skeleton = *frame.skeleton(proto.body_id());
  for (int j = 0; j < geometry::kKinectJointCount; ++j) {
    const v1::SkeletonJoint& in = proto.joints(j);
    const SkeletonJoint& out = skeleton.joints[static_cast<std::size_t>(j)];
    EXPECT_EQ(out.p_K, geometry::Vec3(in.position_m().x(), in.position_m().y(), in.position_m().z()));
    EXPECT_EQ(out.state == JointState::kTracked, in.state() == v1::SkeletonJoint::TRACKED);
    EXPECT_EQ(out.orientation.w(), in.orientation().w());
  }
}

TEST(FrameAssembler, ADepthFrameWithoutItsBodyIndexIsWarnedAndStillHandedOn) {
  const AssembledSession s = assemble_session(without(make_session(), v1::SessionChunk::kBodyIndex, 1));
  const auto frames = all_of<CameraFrame>(s.inputs);
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_TRUE(frames[1].body_index.empty());
  EXPECT_FALSE(frames[1].depth_mm.empty());
  EXPECT_TRUE(warned(s, "CAMERA_FRAME_INCOMPLETE", "body_index"));
}

TEST(FrameAssembler, ASkeletonWithoutDepthMakesAFrameOfItsOwn) {
  const AssembledSession s = assemble_session(without(make_session(), v1::SessionChunk::kDepth, 2));
  const auto frames = all_of<CameraFrame>(s.inputs);
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_TRUE(frames[2].depth_mm.empty());
  EXPECT_NE(frames[2].skeleton(0), nullptr);
  // Its body index matched no depth frame: dropped, named.
  EXPECT_TRUE(frames[2].body_index.empty());
  EXPECT_TRUE(warned(s, "CAMERA_FRAME_UNMATCHED", "body_index"));
}

TEST(FrameAssembler, AColourFrameFarFromEveryCameraFrameIsWarned) {
  std::vector<v1::SessionChunk> chunks = make_session();
  // Half a second after the last camera frame: no frame within a colour period.
  chunks[testing::index_of(chunks, v1::SessionChunk::kColor, 1)].mutable_color()->set_t_us(1'600'000);
  const AssembledSession s = assemble_session(chunks);
  EXPECT_TRUE(all_of<CameraFrame>(s.inputs)[1].color.empty());
  EXPECT_TRUE(warned(s, "CAMERA_FRAME_UNMATCHED", "color"));
}

TEST(FrameAssembler, ACameraChunkOlderThanAFrameHandedOnIsRefusedByName) {
  const std::vector<v1::SessionChunk> chunks = make_session();
  v1::SessionHeader header = chunks.front().header();
  FrameAssembler assembler(header, FrameAssembler::Options{.max_pending_frames = 1});
  std::vector<SessionInput> ready;
  for (int f = 0; f < 3; ++f) {
    assembler.add(chunks[testing::index_of(chunks, v1::SessionChunk::kDepth, f)], cv::Mat(), "chunk", ready);
  }
  ASSERT_GE(all_of<CameraFrame>(ready).size(), 1u);  // at most one frame waits
  const std::size_t handed_on = ready.size();
  // The first frame's skeleton, after that frame was handed on.
  const v1::SessionChunk& late = chunks[testing::index_of(chunks, v1::SessionChunk::kSkeleton, 0)];
  testing::expect_error([&] { assembler.add(late, cv::Mat(), "chunk[9]", ready); }, ErrorCode::kInvalidArgument,
                        "chunk[9].skeleton.t_us");
  EXPECT_EQ(ready.size(), handed_on);  // nothing lost, nothing added
  std::vector<AssemblyWarning> warnings;
  assembler.finish(ready, warnings);
  EXPECT_EQ(all_of<CameraFrame>(ready).size(), 3u);
}

TEST(FrameAssembler, ASecondSkeletonOfOneBodyForOneInstantIsRefused) {
  const std::vector<v1::SessionChunk> chunks = make_session();
  FrameAssembler assembler(chunks.front().header());
  std::vector<SessionInput> ready;
  v1::SessionChunk skeleton = chunks[testing::index_of(chunks, v1::SessionChunk::kSkeleton, 0)];
  assembler.add(skeleton, cv::Mat(), "chunk[1]", ready);
  skeleton.mutable_skeleton()->set_t_us(skeleton.skeleton().t_us() + 500);  // within the same instant
  testing::expect_error([&] { assembler.add(skeleton, cv::Mat(), "chunk[2]", ready); }, ErrorCode::kInvalidArgument,
                        "chunk[2].skeleton.body_id");
}

TEST(FrameAssembler, ABleReceiptWithAMalformedPayloadIsRefused) {
  v1::SyncEvent event;
  event.set_kind(v1::SyncEvent::BLE_BROADCAST_RECEIPT);
  event.set_device_id("wrist_r");
  event.set_payload("ab");
  testing::expect_error([&] { (void)clock_event(event); }, ErrorCode::kInvalidArgument, "sync_event.payload");
}

// Every stage reads the header's cameras through session_cameras(): the forearm stage's strap
// search back-projects with geometry::back_project, the fit casts rays through
// raycast::DepthCamera. With tangential distortion (p1, p2) both put a depth pixel at the same
// point, and both project it back onto that pixel.
TEST(SessionCameras, ADepthPixelIsTheSamePointInTheForearmAndFitPaths) {
  v1::SessionHeader header = make_session().front().header();
  v1::CameraIntrinsics& k = *header.mutable_depth_intrinsics();
  k.set_width(512), k.set_height(424), k.set_fx(365.0), k.set_fy(364.0), k.set_cx(258.0), k.set_cy(210.0);
  k.set_k1(0.09), k.set_k2(-0.27), k.set_k3(0.09), k.set_p1(0.002), k.set_p2(-0.0015);
  const geometry::PinholeCamera depth = session_cameras(header).depth;
  EXPECT_EQ(depth.p1, 0.002);
  EXPECT_EQ(depth.p2, -0.0015);
  const raycast::DepthCamera fit_camera(depth);
  double largest_tangential_px = 0.0;
  for (const double u : {0.0, 100.5, 258.0, 400.0, 511.0}) {
    for (const double v : {0.0, 50.0, 210.0, 423.0}) {
      const double z = 1.7;
      const geometry::Vec3 forearm_p = geometry::back_project(depth, u, v, z);
      const Eigen::Vector3d ray = fit_camera.ray_direction(u, v);
      const Eigen::Vector3d fit_p = ray * (z / ray.z());
      EXPECT_LT((forearm_p - fit_p).norm(), 1e-9) << u << " " << v;
      const auto forearm_uv = geometry::project(depth, fit_p);
      const auto fit_uv = fit_camera.project(forearm_p);
      ASSERT_TRUE(forearm_uv && fit_uv);
      EXPECT_LT((*forearm_uv - geometry::Vec2(u, v)).norm(), 1e-7) << u << " " << v;
      EXPECT_LT((*fit_uv - Eigen::Vector2d(u, v)).norm(), 1e-7) << u << " " << v;
      geometry::PinholeCamera radial_only = depth;
      radial_only.p1 = radial_only.p2 = 0.0;
      largest_tangential_px =
          std::max(largest_tangential_px, (*geometry::project(radial_only, forearm_p) - *forearm_uv).norm());
    }
  }
  EXPECT_GT(largest_tangential_px, 0.5);  // dropping p1, p2 would move the image's corners
}

}  // namespace
}  // namespace posefuse::session
