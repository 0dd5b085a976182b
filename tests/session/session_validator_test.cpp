#include "session/session_validator.hpp"

#include <gtest/gtest.h>

#include <limits>

#include "fixture.hpp"
#include "session/image_codec.hpp"

namespace posefuse::session::testing {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr float kInfF = std::numeric_limits<float>::infinity();

std::string chunk_field(std::size_t i, const std::string& rest) { return "chunk[" + std::to_string(i) + "]" + rest; }

void expect_invalid(const std::vector<SessionChunk>& chunks, const std::string& field) {
  expect_error([&] { validate_all(chunks); }, ErrorCode::kInvalidArgument, field);
}

TEST(SessionValidator, AcceptsFixtureAndCountsIt) {
  const auto session = make_session();
  SessionValidator validator;
  for (const SessionChunk& c : session) validator.check(c);
  EXPECT_NO_THROW(validator.finish());
  EXPECT_TRUE(validator.ended());
  EXPECT_EQ(validator.counts().depth_frames(), 3u);
  EXPECT_EQ(validator.counts().skeleton_frames(), 4u);
  EXPECT_EQ(validator.counts().imu_samples().at("wrist_r"), 70u);
  EXPECT_EQ(validator.counts().audio_frames(), 4800u);
}

TEST(SessionValidator, RejectedChunksKeepTheirStreamPosition) {
  // A caller that skips a rejected chunk and goes on must still get error fields that name the
  // position in the stream, not the count of accepted chunks.
  const auto session = make_session();
  SessionValidator validator;
  validator.check(session[0]);
  const SessionChunk empty;
  expect_error([&] { validator.check(empty); }, ErrorCode::kInvalidArgument, "chunk[1]");
  expect_error([&] { validator.check(empty); }, ErrorCode::kInvalidArgument, "chunk[2]");
  EXPECT_EQ(validator.chunks_checked(), 3u);
}

TEST(SessionValidator, HeaderMustComeFirst) {
  auto session = make_session();
  session.erase(session.begin());
  expect_invalid(session, "chunk[0]");
}

TEST(SessionValidator, OnlyOneHeader) {
  auto session = make_session();
  session.insert(session.begin() + 2, session[0]);
  expect_invalid(session, "chunk[2].header");
}

TEST(SessionValidator, EmptyStreamHasNoHeader) { expect_invalid({}, "header"); }

TEST(SessionValidator, MissingEndMarker) {
  auto session = make_session();
  session.pop_back();
  expect_invalid(session, "end");
}

TEST(SessionValidator, EndCountsMustMatch) {
  auto session = make_session();
  session.back().mutable_end()->set_depth_frames(4);
  expect_invalid(session, chunk_field(session.size() - 1, ".end.depth_frames"));
  session = make_session();
  (*session.back().mutable_end()->mutable_imu_samples())["base"] = 69;
  expect_invalid(session, chunk_field(session.size() - 1, ".end.imu_samples[base]"));
}

TEST(SessionValidator, NothingAfterEnd) {
  auto session = make_session();
  session.push_back(session[1]);
  expect_invalid(session, chunk_field(session.size() - 1, ""));
}

TEST(SessionValidator, EmptyChunk) {
  auto session = make_session();
  session.insert(session.begin() + 1, SessionChunk());
  expect_invalid(session, "chunk[1]");
}

TEST(SessionValidator, HeaderFieldsAreChecked) {
  auto session = make_session();
  session[0].mutable_header()->mutable_depth_intrinsics()->set_fx(kNaN);
  expect_invalid(session, "chunk[0].header.depth_intrinsics.fx");

  session = make_session();
  session[0].mutable_header()->mutable_color_intrinsics()->set_k2(kNaN);
  expect_invalid(session, "chunk[0].header.color_intrinsics.k2");

  session = make_session();
  session[0].mutable_header()->set_format_version(2);
  expect_invalid(session, "chunk[0].header.format_version");

  session = make_session();
  session[0].mutable_header()->mutable_imu_devices(1)->set_device_id("../etc");
  expect_invalid(session, "chunk[0].header.imu_devices[1].device_id");

  session = make_session();
  session[0].mutable_header()->mutable_imu_devices(2)->set_role(v1::ImuDevice::ROLE_UNSPECIFIED);
  expect_invalid(session, "chunk[0].header.imu_devices[2].role");

  session = make_session();
  session[0].mutable_header()->mutable_color_from_depth()->mutable_rotation()->set_w(0.5);
  expect_invalid(session, "chunk[0].header.color_from_depth.rotation");

  session = make_session();
  session[0].mutable_header()->clear_depth_intrinsics();
  expect_invalid(session, "chunk[0].header.depth_intrinsics");
}

// Each stream's timestamp field, set on a copy of the chunk.
void set_t_us(SessionChunk& chunk, std::int64_t t_us) {
  switch (chunk.chunk_case()) {
    case SessionChunk::kDepth: chunk.mutable_depth()->set_t_us(t_us); break;
    case SessionChunk::kBodyIndex: chunk.mutable_body_index()->set_t_us(t_us); break;
    case SessionChunk::kSkeleton: chunk.mutable_skeleton()->set_t_us(t_us); break;
    case SessionChunk::kColor: chunk.mutable_color()->set_t_us(t_us); break;
    case SessionChunk::kImu: chunk.mutable_imu()->set_t_us(0, t_us); break;
    case SessionChunk::kAudio: chunk.mutable_audio()->set_t_us(t_us); break;
    case SessionChunk::kSyncEvent: chunk.mutable_sync_event()->set_t_us(t_us); break;
    default: FAIL() << "not a data chunk";
  }
}

TEST(SessionValidator, TimestampsOutsideTwoToThe53AreRejectedInEveryStream) {
  const auto session = make_session();
  const v1::SessionHeader& header = session[0].header();
  struct Stream {
    SessionChunk::ChunkCase kind;
    const char* field;
  };
  for (const Stream stream :
       {Stream{SessionChunk::kDepth, ".depth.t_us"}, Stream{SessionChunk::kBodyIndex, ".body_index.t_us"},
        Stream{SessionChunk::kSkeleton, ".skeleton.t_us"}, Stream{SessionChunk::kColor, ".color.t_us"},
        Stream{SessionChunk::kImu, ".imu[0].t_us"}, Stream{SessionChunk::kAudio, ".audio.t_us"},
        Stream{SessionChunk::kSyncEvent, ".sync_event.t_us"}}) {
    SCOPED_TRACE(stream.field);
    SessionChunk chunk = session[index_of(session, stream.kind)];
    for (const std::int64_t t_us : {std::numeric_limits<std::int64_t>::min(), std::numeric_limits<std::int64_t>::max(),
                                    kMaxAbsTimestampUs + 1, -kMaxAbsTimestampUs - 1}) {
      set_t_us(chunk, t_us);
      expect_error([&] { validate_chunk(chunk, header, "chunk[9]"); }, ErrorCode::kInvalidArgument,
                   std::string("chunk[9]") + stream.field);
    }
    // The bounds themselves are timestamps (the IMU batch stays in order: its first sample is
    // set, and -2^53 is before the others).
    set_t_us(chunk, -kMaxAbsTimestampUs);
    EXPECT_NO_THROW(validate_chunk(chunk, header, "chunk[9]"));
    if (stream.kind != SessionChunk::kImu) {
      set_t_us(chunk, kMaxAbsTimestampUs);
      EXPECT_NO_THROW(validate_chunk(chunk, header, "chunk[9]"));
    }
  }
}

TEST(SessionValidator, HeaderImageSizesAreBoundedInPixels) {
  // Each side within kMaxImageSide, but more pixels than a frame of that camera may have.
  auto session = make_session();
  session[0].mutable_header()->mutable_depth_intrinsics()->set_width(2048);
  session[0].mutable_header()->mutable_depth_intrinsics()->set_height(1024);
  expect_invalid(session, "chunk[0].header.depth_intrinsics.width");
  session = make_session();
  session[0].mutable_header()->mutable_color_intrinsics()->set_width(8192);
  session[0].mutable_header()->mutable_color_intrinsics()->set_height(8192);
  expect_invalid(session, "chunk[0].header.color_intrinsics.width");
}

TEST(SessionValidator, WrongSizeRawDepth) {
  auto session = make_session();
  const std::size_t i = index_of(session, SessionChunk::kDepth, 1);
  v1::DepthFrame* depth = session[i].mutable_depth();
  *depth = encode_depth(decode_depth(*depth), v1::DepthFrame::RAW_U16_LE, depth->t_us());
  EXPECT_NO_THROW(validate_all(session));
  depth->mutable_data()->pop_back();
  expect_invalid(session, chunk_field(i, ".depth.data"));
}

TEST(SessionValidator, DepthSizeMustMatchHeader) {
  auto session = make_session();
  const std::size_t i = index_of(session, SessionChunk::kDepth);
  session[i].mutable_depth()->set_width(17);
  expect_invalid(session, chunk_field(i, ".depth.width"));
}

TEST(SessionValidator, UndecodablePngDepth) {
  auto session = make_session();
  const std::size_t i = index_of(session, SessionChunk::kDepth, 2);
  std::string* data = session[i].mutable_depth()->mutable_data();
  data->resize(data->size() / 2);  // header intact, pixel data cut
  expect_invalid(session, chunk_field(i, ".depth.data"));
}

TEST(SessionValidator, EightBitPngIsNotDepth) {
  auto session = make_session();
  const std::size_t depth = index_of(session, SessionChunk::kDepth);
  const std::size_t ids = index_of(session, SessionChunk::kBodyIndex);
  session[depth].mutable_depth()->set_data(session[ids].body_index().data());
  expect_invalid(session, chunk_field(depth, ".depth.data"));
}

TEST(SessionValidator, ZstdDepthIsChecked) {
  auto session = make_session();
  const std::size_t i = index_of(session, SessionChunk::kDepth);
  v1::DepthFrame* depth = session[i].mutable_depth();
  *depth = encode_depth(decode_depth(*depth), v1::DepthFrame::ZSTD_U16_LE, depth->t_us());
  EXPECT_NO_THROW(validate_all(session));
  depth->mutable_data()->back() ^= 0x5A;
  expect_invalid(session, chunk_field(i, ".depth.data"));
}

TEST(SessionValidator, BodyIndexValuesAreBodyIdsOrBackground) {
  auto session = make_session();
  const std::size_t i = index_of(session, SessionChunk::kBodyIndex);
  cv::Mat ids = decode_body_index(session[i].body_index());
  ids.at<std::uint8_t>(3, 3) = 7;
  *session[i].mutable_body_index() = encode_body_index(ids, v1::BodyIndexFrame::RAW_U8, session[i].body_index().t_us());
  expect_invalid(session, chunk_field(i, ".body_index.data"));
}

TEST(SessionValidator, NaNInImu) {
  auto session = make_session();
  const std::size_t i = index_of(session, SessionChunk::kImu, 2);
  session[i].mutable_imu()->set_gyr_rad_s(3 * 5 + 1, std::numeric_limits<float>::quiet_NaN());
  expect_invalid(session, chunk_field(i, ".imu[5].gyr_rad_s"));
}

TEST(SessionValidator, InfiniteMagIsRejectedButNaNMagIsAMissingReading) {
  auto session = make_session();
  EXPECT_NO_THROW(validate_all(session));  // the fixture has a NaN mag sample
  const std::size_t i = index_of(session, SessionChunk::kImu);
  session[i].mutable_imu()->set_mag_ut(3, kInfF);
  expect_invalid(session, chunk_field(i, ".imu[1].mag_uT"));
}

TEST(SessionValidator, ImuArraySizes) {
  auto session = make_session();
  const std::size_t i = index_of(session, SessionChunk::kImu);
  session[i].mutable_imu()->mutable_acc_m_s2()->RemoveLast();
  expect_invalid(session, chunk_field(i, ".imu.acc_m_s2"));
}

TEST(SessionValidator, ImuDeviceMustBeInHeader) {
  auto session = make_session();
  const std::size_t i = index_of(session, SessionChunk::kImu);
  session[i].mutable_imu()->set_device_id("ankle");
  expect_invalid(session, chunk_field(i, ".imu.device_id"));
}

TEST(SessionValidator, OutOfOrderDepthTimestamps) {
  auto session = make_session();
  const std::size_t i = index_of(session, SessionChunk::kDepth, 2);
  session[i].mutable_depth()->set_t_us(session[index_of(session, SessionChunk::kDepth, 1)].depth().t_us());
  expect_invalid(session, chunk_field(i, ".depth.t_us"));
}

TEST(SessionValidator, OutOfOrderImuAcrossBatches) {
  auto session = make_session();
  // Second batch of the first device starts at the first batch's last sample time.
  const std::size_t first = index_of(session, SessionChunk::kImu, 0);
  const std::string device = session[first].imu().device_id();
  std::size_t second = first + 1;
  while (!(session[second].has_imu() && session[second].imu().device_id() == device)) ++second;
  const auto& t = session[first].imu().t_us();
  const std::int64_t shift = t[t.size() - 1] - session[second].imu().t_us(0);
  for (auto& t_us : *session[second].mutable_imu()->mutable_t_us()) t_us += shift;
  expect_invalid(session, chunk_field(second, ".imu[0].t_us"));
}

TEST(SessionValidator, OutOfOrderWithinImuBatch) {
  auto session = make_session();
  const std::size_t i = index_of(session, SessionChunk::kImu);
  session[i].mutable_imu()->set_t_us(4, session[i].imu().t_us(3));
  expect_invalid(session, chunk_field(i, ".imu[4].t_us"));
}

TEST(SessionValidator, SkeletonOrderIsPerBody) {
  auto session = make_session();
  EXPECT_NO_THROW(validate_all(session));  // body 2 at frame 1 interleaves with body 0
  const std::size_t i = index_of(session, SessionChunk::kSkeleton, 1);
  session[i].mutable_skeleton()->set_t_us(session[i].skeleton().t_us() - 40'000);
  expect_invalid(session, chunk_field(i, ".skeleton.t_us"));
}

TEST(SessionValidator, StreamTimeIsTheLongestSpanWithinOneStream) {
  const auto session = make_session();
  SessionValidator validator;
  validator.check(session[0]);
  EXPECT_EQ(validator.stream_time_us(), 0);
  for (std::size_t i = 1; i < session.size(); ++i) validator.check(session[i]);
  // The fixture's longest stream is an IMU's: 70 samples at 80 Hz. Its devices' clocks start
  // up to 4 s apart (wrist_l at 0.95 s, wrist_r at 5 s), which must not count as recording.
  EXPECT_EQ(validator.stream_time_us(), 69 * 12'500);
}

TEST(SessionValidator, RejectedTimestampsAddNoStreamTime) {
  const auto session = make_session();
  const std::size_t last_depth = index_of(session, SessionChunk::kDepth, 2);
  SessionValidator validator;
  for (std::size_t i = 0; i <= last_depth; ++i) validator.check(session[i]);
  const std::int64_t before = validator.stream_time_us();
  ASSERT_GT(before, 0);
  SessionChunk chunk = session[last_depth];
  // Backwards, and beyond +-2^53 us either way: refused, so the stream time stays.
  for (const std::int64_t t_us : {session[last_depth].depth().t_us() - 1'000'000, kMaxAbsTimestampUs + 1,
                                  std::numeric_limits<std::int64_t>::max(), -kMaxAbsTimestampUs - 1}) {
    SCOPED_TRACE(t_us);
    chunk.mutable_depth()->set_t_us(t_us);
    EXPECT_THROW(validator.check(chunk), Error);
    EXPECT_EQ(validator.stream_time_us(), before);
  }
  // A jump forward the validator accepts does count, but no further than the +-2^53 us range.
  chunk.mutable_depth()->set_t_us(kMaxAbsTimestampUs);
  validator.check(chunk);
  EXPECT_EQ(validator.stream_time_us(),
            kMaxAbsTimestampUs - session[index_of(session, SessionChunk::kDepth)].depth().t_us());
}

TEST(SessionValidator, UnknownEnumValues) {
  auto session = make_session();
  const std::size_t depth = index_of(session, SessionChunk::kDepth);
  session[depth].mutable_depth()->set_encoding(static_cast<v1::DepthFrame::Encoding>(9));
  expect_invalid(session, chunk_field(depth, ".depth.encoding"));

  session = make_session();
  const std::size_t skeleton = index_of(session, SessionChunk::kSkeleton);
  session[skeleton].mutable_skeleton()->mutable_joints(4)->set_state(v1::SkeletonJoint::STATE_UNSPECIFIED);
  expect_invalid(session, chunk_field(skeleton, ".skeleton.joints[4].state"));

  session = make_session();
  const std::size_t sync = index_of(session, SessionChunk::kSyncEvent);
  session[sync].mutable_sync_event()->set_kind(static_cast<v1::SyncEvent::Kind>(42));
  expect_invalid(session, chunk_field(sync, ".sync_event.kind"));

  session = make_session();
  session[0].mutable_header()->set_sex(static_cast<v1::SessionHeader::Sex>(-3));
  expect_invalid(session, "chunk[0].header.sex");
}

TEST(SessionValidator, SkeletonNeeds25FiniteJoints) {
  auto session = make_session();
  const std::size_t i = index_of(session, SessionChunk::kSkeleton, 2);
  session[i].mutable_skeleton()->mutable_joints()->RemoveLast();
  expect_invalid(session, chunk_field(i, ".skeleton.joints"));

  session = make_session();
  session[i].mutable_skeleton()->mutable_joints(10)->mutable_position_m()->set_y(kNaN);
  expect_invalid(session, chunk_field(i, ".skeleton.joints[10].position_m.y"));

  session = make_session();
  session[i].mutable_skeleton()->mutable_joints(3)->mutable_orientation()->set_x(2.0);
  expect_invalid(session, chunk_field(i, ".skeleton.joints[3].orientation"));
}

TEST(SessionValidator, ColorFrameMustMatchItsBytes) {
  auto session = make_session();
  const std::size_t jpeg = index_of(session, SessionChunk::kColor, 1);
  ASSERT_EQ(session[jpeg].color().encoding(), v1::ColorFrame::JPEG);
  session[jpeg].mutable_color()->set_encoding(v1::ColorFrame::PNG);
  expect_invalid(session, chunk_field(jpeg, ".color.data"));

  session = make_session();
  session[0].mutable_header()->clear_color_intrinsics();
  expect_invalid(session, chunk_field(index_of(session, SessionChunk::kColor), ".color"));
}

TEST(SessionValidator, AudioMustMatchHeader) {
  auto session = make_session();
  const std::size_t i = index_of(session, SessionChunk::kAudio, 1);
  session[i].mutable_audio()->set_channels(2);
  expect_invalid(session, chunk_field(i, ".audio.channels"));

  session = make_session();
  session[i].mutable_audio()->mutable_pcm_s16le()->pop_back();
  expect_invalid(session, chunk_field(i, ".audio.pcm_s16le"));
}

TEST(SessionValidator, SyncEventDeviceMustBeKnown) {
  auto session = make_session();
  const std::size_t i = index_of(session, SessionChunk::kSyncEvent, 1);
  session[i].mutable_sync_event()->set_device_id("phone");
  expect_invalid(session, chunk_field(i, ".sync_event.device_id"));
}

TEST(SessionValidator, MessagesAreReadable) {
  auto session = make_session();
  const std::size_t i = index_of(session, SessionChunk::kDepth, 1);
  v1::DepthFrame* depth = session[i].mutable_depth();
  *depth = encode_depth(decode_depth(*depth), v1::DepthFrame::RAW_U16_LE, depth->t_us());
  depth->mutable_data()->resize(380);
  try {
    validate_all(session);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              chunk_field(i, ".depth.data") + ": has 380 bytes, expected 384 (16x12 RAW_U16_LE)");
  }
}

}  // namespace
}  // namespace posefuse::session::testing
