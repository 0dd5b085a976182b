// SessionPipeline and the IMU orientation stage, without gRPC: the demo session (client/) in,
// FitResults out.
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <algorithm>

#include "client/demo_session.hpp"
#include "common/error.hpp"
#include "geometry/quaternion.hpp"
#include "session/imu_batch.hpp"
#include "session/mag_calibration_option.hpp"
#include "session/pipeline.hpp"
#include "session/stages/default_stages.hpp"

namespace posefuse::session {
namespace {

using std::numbers::pi;

class CollectingSink : public ResultSink {
 public:
  void emit(v1::FitResult&& result) override { results.push_back(std::move(result)); }

  std::vector<v1::FitResult> of(v1::FitResult::ResultCase kind) const {
    std::vector<v1::FitResult> out;
    for (const auto& r : results) {
      if (r.result_case() == kind) out.push_back(r);
    }
    return out;
  }
  std::vector<v1::ItemError> item_errors() const {
    std::vector<v1::ItemError> out;
    for (const auto& r : of(v1::FitResult::kItemError)) out.push_back(r.item_error());
    return out;
  }
  // device_id -> (t_us, W_from_A) of every orientation result, in order.
  std::map<std::string, std::vector<std::pair<std::int64_t, geometry::Quat>>> orientations() const {
    std::map<std::string, std::vector<std::pair<std::int64_t, geometry::Quat>>> out;
    for (const auto& r : of(v1::FitResult::kImuOrientations)) {
      const auto& b = r.imu_orientations();
      for (int i = 0; i < b.t_us_size(); ++i) {
        out[b.device_id()].emplace_back(b.t_us(i), geometry::Quat(b.w_from_a(4 * i), b.w_from_a(4 * i + 1),
                                                                  b.w_from_a(4 * i + 2), b.w_from_a(4 * i + 3)));
      }
    }
    return out;
  }

  std::vector<v1::FitResult> results;
};

void run(const std::vector<v1::SessionChunk>& chunks, CollectingSink& sink) {
  SessionPipeline pipeline(make_default_stages(), sink);
  for (const auto& chunk : chunks) pipeline.push(chunk);
  pipeline.close();
}

std::size_t index_of_nth(const std::vector<v1::SessionChunk>& chunks, v1::SessionChunk::ChunkCase kind, int n,
                         const std::string& device = "") {
  int seen = 0;
  for (std::size_t i = 0; i < chunks.size(); ++i) {
    if (chunks[i].chunk_case() != kind) continue;
    if (!device.empty() && chunks[i].imu().device_id() != device) continue;
    if (seen++ == n) return i;
  }
  ADD_FAILURE() << "no such chunk";
  return 0;
}

std::uint64_t total_samples(const std::vector<v1::SessionChunk>& chunks, const std::string& device) {
  std::uint64_t n = 0;
  for (const auto& c : chunks) {
    if (c.has_imu() && c.imu().device_id() == device) n += c.imu().t_us_size();
  }
  return n;
}

TEST(SessionPipeline, DemoSessionGivesAnOrientationForEveryImuSample) {
  const auto chunks = demo::make_demo_session();
  CollectingSink sink;
  run(chunks, sink);

  EXPECT_TRUE(sink.item_errors().empty());
  const auto orientations = sink.orientations();
  for (const char* device : {demo::kArmDevice, demo::kBaseDevice}) {
    SCOPED_TRACE(device);
    std::vector<std::int64_t> input_t_us;
    for (const auto& c : chunks) {
      if (c.has_imu() && c.imu().device_id() == device) {
        input_t_us.insert(input_t_us.end(), c.imu().t_us().begin(), c.imu().t_us().end());
      }
    }
    ASSERT_EQ(input_t_us.size(), 800u);  // 10 s at 80 Hz
    const auto& out = orientations.at(device);
    ASSERT_EQ(out.size(), input_t_us.size());
    for (std::size_t i = 0; i < out.size(); ++i) {
      EXPECT_EQ(out[i].first, input_t_us[i]);
      EXPECT_NEAR(out[i].second.norm(), 1.0, 1e-9);
      if (i > 0) {
        EXPECT_GE(out[i].second.coeffs().dot(out[i - 1].second.coeffs()), 0.0);
      }
    }
  }

  // The last three results: calibration report, progress, summary.
  ASSERT_GE(sink.results.size(), 3u);
  const auto n = sink.results.size();
  ASSERT_TRUE(sink.results[n - 3].has_calibration());
  ASSERT_TRUE(sink.results[n - 2].has_progress());
  ASSERT_TRUE(sink.results[n - 1].has_summary());
  const v1::Summary& summary = sink.results[n - 1].summary();
  EXPECT_EQ(summary.chunks(), chunks.size());
  EXPECT_EQ(summary.depth_frames(), 300u);
  EXPECT_EQ(summary.item_errors(), 0u);
  EXPECT_NEAR(summary.stream_duration_s(), 299.0 / 30.0, 1e-5);
  EXPECT_EQ(sink.results[n - 2].progress().chunks_processed(), chunks.size());

  const v1::CalibrationReport& report = sink.results[n - 3].calibration();
  ASSERT_EQ(report.imus_size(), 2);
  EXPECT_EQ(report.imus(0).device_id(), demo::kArmDevice);
  EXPECT_EQ(report.imus(1).device_id(), demo::kBaseDevice);
  // The base rests all session: its bias estimate must approach the generator's
  // (-0.004, 0.006, 0.002) rad/s; 0.002 rad/s is 0.11 deg/s.
  const auto& bias = report.imus(1).gyro_bias_rad_s();
  EXPECT_NEAR(bias.x(), -0.004, 0.002);
  EXPECT_NEAR(bias.y(), 0.006, 0.002);
  EXPECT_NEAR(bias.z(), 0.002, 0.002);
  // The filter learned the demo's 49 uT field.
  EXPECT_NEAR(report.imus(1).mag_field_ut(), 49.0, 1.0);
}

TEST(SessionPipeline, ArmOrientationFollowsTheDemoTruth) {
  const auto chunks = demo::make_demo_session();
  CollectingSink sink;
  run(chunks, sink);
  const auto arm = sink.orientations().at(demo::kArmDevice);
  double sum_deg = 0.0, max_deg = 0.0;
  int n = 0;
  for (const auto& [t_us, W_from_A] : arm) {
    const double t_s = static_cast<double>(t_us - demo::kArmClockStartUs) * 1e-6;
    if (t_s < 1.0) continue;  // start-up
    const double error_deg = geometry::angle_between(W_from_A, demo::demo_arm_W_from_A(t_s)) * 180.0 / pi;
    sum_deg += error_deg;
    max_deg = std::max(max_deg, error_deg);
    ++n;
  }
  ASSERT_GT(n, 0);
  RecordProperty("mean_error_deg", std::to_string(sum_deg / n));
  RecordProperty("max_error_deg", std::to_string(max_deg));
  EXPECT_LT(sum_deg / n, 3.0);
  EXPECT_LT(max_deg, 8.0);
}

TEST(SessionPipeline, NanInImuIsAnItemErrorAndTheRestCompletes) {
  auto chunks = demo::make_demo_session();
  const std::size_t bad = index_of_nth(chunks, v1::SessionChunk::kImu, 5, demo::kArmDevice);
  chunks[bad].mutable_imu()->set_gyr_rad_s(4, std::nanf(""));
  CollectingSink sink;
  run(chunks, sink);

  const auto errors = sink.item_errors();
  ASSERT_GE(errors.size(), 1u);
  EXPECT_EQ(errors[0].code(), "invalid argument");
  EXPECT_EQ(errors[0].field(), "chunk[" + std::to_string(bad) + "].imu[1].gyr_rad_s");
  // The end marker counted the rejected batch; the mismatch is reported, nothing else.
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_EQ(errors[1].field().rfind("chunk[" + std::to_string(chunks.size() - 1) + "].end.", 0), 0u)
      << errors[1].field();
  const auto arm = sink.orientations().at(demo::kArmDevice);
  EXPECT_EQ(arm.size(), total_samples(chunks, demo::kArmDevice) - 32);
  EXPECT_EQ(sink.orientations().at(demo::kBaseDevice).size(), 800u);
  ASSERT_TRUE(sink.results.back().has_summary());
  EXPECT_EQ(sink.results.back().summary().item_errors(), 2u);
}

TEST(SessionPipeline, WrongDepthSizeNamesTheFieldAndLaterChunksKeepTheirStreamIndex) {
  auto chunks = demo::make_demo_session();
  const std::size_t bad_depth = index_of_nth(chunks, v1::SessionChunk::kDepth, 3);
  chunks[bad_depth].mutable_depth()->set_width(63);
  // A second bad chunk later: its field must carry its own position in the stream, although
  // the validator accepted one chunk fewer than the stream holds.
  const std::size_t bad_skeleton = index_of_nth(chunks, v1::SessionChunk::kSkeleton, 10);
  chunks[bad_skeleton].mutable_skeleton()->mutable_joints()->RemoveLast();
  CollectingSink sink;
  run(chunks, sink);

  const auto errors = sink.item_errors();
  ASSERT_GE(errors.size(), 2u);
  EXPECT_EQ(errors[0].field(), "chunk[" + std::to_string(bad_depth) + "].depth.width");
  EXPECT_EQ(errors[1].field().rfind("chunk[" + std::to_string(bad_skeleton) + "].skeleton", 0), 0u)
      << errors[1].field();
  ASSERT_TRUE(sink.results.back().has_summary());
  EXPECT_EQ(sink.results.back().summary().depth_frames(), 299u);
  EXPECT_EQ(sink.orientations().at(demo::kArmDevice).size(), 800u);
}

TEST(SessionPipeline, OutOfOrderImuBatchIsRejectedAndTheStreamGoesOn) {
  auto chunks = demo::make_demo_session();
  const std::size_t first = index_of_nth(chunks, v1::SessionChunk::kImu, 4, demo::kArmDevice);
  const std::size_t second = index_of_nth(chunks, v1::SessionChunk::kImu, 5, demo::kArmDevice);
  std::swap(chunks[first], chunks[second]);
  CollectingSink sink;
  run(chunks, sink);

  const auto errors = sink.item_errors();
  ASSERT_GE(errors.size(), 1u);
  EXPECT_EQ(errors[0].field(), "chunk[" + std::to_string(second) + "].imu[0].t_us");
  const auto arm = sink.orientations().at(demo::kArmDevice);
  EXPECT_EQ(arm.size(), 800u - 32u);
  for (std::size_t i = 1; i < arm.size(); ++i) {
    EXPECT_GT(arm[i].first, arm[i - 1].first);
  }
  EXPECT_TRUE(sink.results.back().has_summary());
}

TEST(SessionPipeline, SessionEndingErrorsAreThrownWithTheField) {
  const auto chunks = demo::make_demo_session();
  CollectingSink sink;
  {
    SessionPipeline pipeline(make_default_stages(), sink);
    try {
      pipeline.push(chunks[1]);  // a data chunk before the header
      FAIL() << "no error";
    } catch (const Error& e) {
      EXPECT_EQ(e.field(), "chunk[0]");
    }
  }
  {
    auto header = chunks[0];
    header.mutable_header()->mutable_depth_intrinsics()->set_fx(-1.0);
    SessionPipeline pipeline(make_default_stages(), sink);
    try {
      pipeline.push(header);
      FAIL() << "no error";
    } catch (const Error& e) {
      EXPECT_EQ(e.field(), "chunk[0].header.depth_intrinsics.fx");
    }
  }
  {
    SessionPipeline pipeline(make_default_stages(), sink);
    for (std::size_t i = 0; i + 1 < chunks.size(); ++i) pipeline.push(chunks[i]);
    try {
      pipeline.close();
      FAIL() << "no error";
    } catch (const Error& e) {
      EXPECT_EQ(e.field(), "end");
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    }
  }
  {
    SessionPipeline pipeline(make_default_stages(), sink);
    for (const auto& chunk : chunks) pipeline.push(chunk);
    EXPECT_TRUE(pipeline.ended());
    try {
      pipeline.push(chunks[1]);
      FAIL() << "no error";
    } catch (const Error& e) {
      EXPECT_EQ(e.field(), "chunk[" + std::to_string(chunks.size()) + "]");
    }
  }
}

TEST(SessionPipeline, BadStageOptionEndsTheSession) {
  auto chunks = demo::make_demo_session();
  (*chunks[0].mutable_header()->mutable_options())["imu.tau_acc_s"] = "-2";
  CollectingSink sink;
  SessionPipeline pipeline(make_default_stages(), sink);
  try {
    pipeline.push(chunks[0]);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.field(), "header.options[imu.tau_acc_s]");
  }
}

// A key under a stage's prefix that no stage declares is most likely misspelt: a warning names it
// and the nearest declared key; metadata under other prefixes and declared keys pass unremarked.
TEST(SessionPipeline, AMisspeltStageOptionIsWarnedAboutWithTheNearestKey) {
  auto chunks = demo::make_demo_session();
  auto& options = *chunks[0].mutable_header()->mutable_options();
  options["fit.smoothing_frame"] = "5";
  options["forearm.no_such_thing_at_all"] = "1";
  options["sim.seed"] = "7";
  options["fit.smoothing_frames"] = "3";
  options[mag_calibration_option_key(demo::kArmDevice)] = "0 0 0 1 0 0 0 1 0 0 0 1";
  CollectingSink sink;
  SessionPipeline pipeline(make_default_stages(), sink);
  pipeline.push(chunks[0]);
  std::map<std::string, std::string> warned;  // field -> message
  for (const auto& r : sink.of(v1::FitResult::kWarning)) {
    if (r.warning().code() == "OPTION_UNKNOWN") warned[r.warning().field()] = r.warning().message();
  }
  ASSERT_EQ(warned.size(), 2u);
  EXPECT_NE(warned["header.options[fit.smoothing_frame]"].find("did you mean 'fit.smoothing_frames'?"),
            std::string::npos)
      << warned["header.options[fit.smoothing_frame]"];
  EXPECT_NE(warned["header.options[forearm.no_such_thing_at_all]"].find("ignored"), std::string::npos);
  EXPECT_EQ(warned["header.options[forearm.no_such_thing_at_all]"].find("did you mean"), std::string::npos);
}

// A magnetometer calibration in the header (paper 1 eq. 3) is applied before the filter: hard
// iron added to the arm IMU's readings and the same offset given as its calibration leave the
// orientations as they were; without the calibration the heading is off.
TEST(SessionPipeline, MagCalibrationFromTheHeaderUndoesHardIron) {
  const auto clean = demo::make_demo_session();
  const imu::Vec3 hard_iron_uT(12.0, -8.0, 5.0);
  auto with_iron = clean;
  for (auto& chunk : with_iron) {
    if (!chunk.has_imu() || chunk.imu().device_id() != demo::kArmDevice) continue;
    auto samples = samples_from_batch(chunk.imu());
    for (auto& sample : samples) sample.mag_uT += hard_iron_uT;
    *chunk.mutable_imu() = batch_from_samples(demo::kArmDevice, samples);
  }
  auto calibrated = with_iron;
  imu::MagCalibration calibration;
  calibration.center_uT = hard_iron_uT;
  (*calibrated[0].mutable_header()->mutable_options())[mag_calibration_option_key(demo::kArmDevice)] =
      format_mag_calibration(calibration);
  CollectingSink reference, uncorrected, corrected;
  run(clean, reference);
  run(with_iron, uncorrected);
  run(calibrated, corrected);
  const auto expected = reference.orientations().at(demo::kArmDevice);
  const auto off = uncorrected.orientations().at(demo::kArmDevice);
  const auto fixed = corrected.orientations().at(demo::kArmDevice);
  ASSERT_EQ(fixed.size(), expected.size());
  double off_max = 0.0, fixed_max = 0.0;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    off_max = std::max(off_max, geometry::angle_between(off[i].second, expected[i].second));
    fixed_max = std::max(fixed_max, geometry::angle_between(fixed[i].second, expected[i].second));
  }
  EXPECT_GT(off_max * 180.0 / pi, 5.0);
  EXPECT_LT(fixed_max * 180.0 / pi, 0.01);  // the wire's float readings round differently
  const auto calibrations = corrected.of(v1::FitResult::kCalibration);
  ASSERT_EQ(calibrations.size(), 1u);
  for (const auto& imu : calibrations[0].calibration().imus()) {
    EXPECT_EQ(imu.calibrated(), imu.device_id() == demo::kArmDevice) << imu.device_id();
  }
}

TEST(SessionPipeline, BadMagCalibrationOptionEndsTheSession) {
  const std::string key = mag_calibration_option_key(demo::kArmDevice);
  for (const std::string bad : {"1 2 3", "0 0 0 1 0 0 0 1 0 0 0 nan", "0 0 0 1 0 0 1 0 0 0 0 1"}) {
    auto chunks = demo::make_demo_session();
    (*chunks[0].mutable_header()->mutable_options())[key] = bad;
    CollectingSink sink;
    SessionPipeline pipeline(make_default_stages(), sink);
    try {
      pipeline.push(chunks[0]);
      FAIL() << "no error for '" << bad << "'";
    } catch (const Error& e) {
      EXPECT_EQ(e.field(), "header.options[" + key + "]") << bad;
    }
  }
}

TEST(MagCalibrationOption, RoundTripIsExact) {
  imu::MagCalibration c;
  c.center_uT = imu::Vec3(-10.681608086968694, 7.1, 1e-3);
  c.correction << 1.01, -0.0187, 0.1, -0.0187, 0.99, 0.013, 0.1, 0.013, 1.0 / 3.0;
  const imu::MagCalibration back = parse_mag_calibration(format_mag_calibration(c), "f");
  EXPECT_EQ(back.center_uT, c.center_uT);
  EXPECT_EQ(back.correction, c.correction);
}

TEST(SessionPipeline, TooManyBadChunksEndTheSession) {
  auto chunks = demo::make_demo_session();
  CollectingSink sink;
  PipelineOptions options;
  options.max_item_errors = 3;
  SessionPipeline pipeline(make_default_stages(), sink, options);
  pipeline.push(chunks[0]);
  v1::SessionChunk empty;  // no chunk kind set
  for (int i = 0; i < 3; ++i) pipeline.push(empty);
  EXPECT_THROW(pipeline.push(empty), Error);
}

// A stage plugged in beside the IMU stage sees every accepted chunk in order, finishes once and
// contributes to the single calibration report; it receives the earlier stages' results.
class RecordingStage : public Stage {
 public:
  explicit RecordingStage(std::vector<std::string>& log) : log_(log) {}
  std::string_view name() const override { return "recording"; }
  std::string_view description() const override { return "test stage"; }
  void start(const v1::SessionHeader&, StageOutput&) override { log_.push_back("start"); }
  std::vector<ValueKind> consumes() const override { return {ValueKind::kImuOrientations}; }
  void on_camera_frame(const CameraFrame& frame, StageOutput&) override {
    if (!frame.depth_mm.empty()) {
      log_.push_back("depth");
      if (log_.size() == 3) throw_precondition("depth", "this stage rejects the second frame");
    }
  }
  // Values of the stages before this one (the IMU stage's orientations), as they are handed on.
  void on_value(const StageValue& value, StageOutput&) override {
    if (std::holds_alternative<ImuOrientations>(value)) ++orientation_batches_seen;
  }
  void finish(StageOutput& out) override {
    log_.push_back("finish");
    out.calibration().mutable_body_shape()->set_estimated(true);
    out.warn("TEST_WARNING", "stage", "from the test stage");
  }

  int orientation_batches_seen = 0;

 private:
  std::vector<std::string>& log_;
};

TEST(SessionPipeline, PluggedStageSeesChunksInOrderAndStageErrorsAreItemErrors) {
  const auto chunks = demo::make_demo_session();
  std::vector<std::string> log;
  std::vector<std::unique_ptr<Stage>> stages = make_default_stages();
  auto recording = std::make_unique<RecordingStage>(log);
  RecordingStage& recorder = *recording;
  stages.push_back(std::move(recording));
  CollectingSink sink;
  SessionPipeline pipeline(std::move(stages), sink);
  for (const auto& chunk : chunks) pipeline.push(chunk);
  pipeline.close();

  ASSERT_EQ(log.size(), 302u);
  EXPECT_EQ(recorder.orientation_batches_seen, static_cast<int>(sink.of(v1::FitResult::kImuOrientations).size()));
  EXPECT_GT(recorder.orientation_batches_seen, 0);
  EXPECT_EQ(log.front(), "start");
  EXPECT_EQ(log.back(), "finish");
  const auto errors = sink.item_errors();
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_EQ(errors[0].code(), "failed precondition");
  EXPECT_EQ(errors[0].field(), "depth");
  const auto calibrations = sink.of(v1::FitResult::kCalibration);
  ASSERT_EQ(calibrations.size(), 1u);
  EXPECT_TRUE(calibrations[0].calibration().body_shape().estimated());
  EXPECT_EQ(calibrations[0].calibration().imus_size(), 2);
  // The test stage's warning, next to the forearm stage's (the demo has no camera alignment).
  const auto warnings = sink.of(v1::FitResult::kWarning);
  EXPECT_EQ(std::count_if(warnings.begin(), warnings.end(),
                          [](const v1::FitResult& r) { return r.warning().code() == "TEST_WARNING"; }),
            1);
  EXPECT_EQ(sink.results.back().summary().warnings(), warnings.size());
  EXPECT_EQ(sink.results.back().summary().item_errors(), 1u);
}

// A stage with a problem on every depth frame (300 in the demo session) and one other.
class EveryFrameWarningStage : public Stage {
 public:
  std::string_view name() const override { return "every_frame_warning"; }
  std::string_view description() const override { return "test stage"; }
  void start(const v1::SessionHeader&, StageOutput&) override {}
  void on_camera_frame(const CameraFrame& frame, StageOutput& out) override {
    if (!frame.depth_mm.empty()) out.warn("TEST_EVERY_FRAME", "frame.depth_mm", "t_us=" + std::to_string(frame.t_us));
  }
  void finish(StageOutput& out) override { out.warn("TEST_ONCE", "stage", "once"); }
};

TEST(SessionPipeline, AWarningThatRepeatsEveryFrameIsListedTenTimesThenCounted) {
  std::vector<std::unique_ptr<Stage>> stages;
  stages.push_back(std::make_unique<EveryFrameWarningStage>());
  CollectingSink sink;
  SessionPipeline pipeline(std::move(stages), sink);
  for (const auto& chunk : demo::make_demo_session()) pipeline.push(chunk);
  pipeline.close();

  const auto warnings = sink.of(v1::FitResult::kWarning);
  std::vector<std::string> every_frame;
  for (const v1::FitResult& r : warnings) {
    if (r.warning().code() == "TEST_EVERY_FRAME") every_frame.push_back(r.warning().message());
  }
  ASSERT_EQ(every_frame.size(), 11u);  // the first ten, then how many more
  EXPECT_EQ(every_frame.front(), "t_us=10000000");
  EXPECT_EQ(every_frame.back(),
            "290 more TEST_EVERY_FRAME warnings for frame.depth_mm were not listed (300 in all; the first 10 are)");
  EXPECT_EQ(std::count_if(warnings.begin(), warnings.end(),
                          [](const v1::FitResult& r) { return r.warning().code() == "TEST_ONCE"; }),
            1);
  EXPECT_EQ(sink.results.back().summary().warnings(), warnings.size());
}

// Data flows one way: a stage that reads what only a later stage hands on (here the forearm
// orientations, put before the forearm stage) is refused when the pipeline is built, naming it.
class ForearmReaderStage : public Stage {
 public:
  std::string_view name() const override { return "forearm_reader"; }
  std::string_view description() const override { return "test stage"; }
  std::vector<ValueKind> consumes() const override { return {ValueKind::kForearmOrientations}; }
  void start(const v1::SessionHeader&, StageOutput&) override {}
  void finish(StageOutput&) override {}
};

TEST(SessionPipeline, AStageCannotDependOnALaterStage) {
  CollectingSink sink;
  std::vector<std::unique_ptr<Stage>> stages = make_default_stages();
  stages.insert(stages.begin() + 1, std::make_unique<ForearmReaderStage>());  // after imu, before forearm
  try {
    SessionPipeline pipeline(std::move(stages), sink);
    ADD_FAILURE() << "the pipeline accepted a stage before the stage it depends on";
  } catch (const Error& error) {
    EXPECT_EQ(error.field(), "stages");
    EXPECT_NE(std::string(error.what()).find("'forearm_reader' consumes forearm_orientations"), std::string::npos)
        << error.what();
  }
  // After the forearm stage it is accepted, as the default order is.
  std::vector<std::unique_ptr<Stage>> in_order = make_default_stages();
  in_order.push_back(std::make_unique<ForearmReaderStage>());
  EXPECT_NO_THROW(SessionPipeline(std::move(in_order), sink));
}

// Values flow one way: what a stage hands on reaches the later stages that consume its kind
// inside that call, before their own call for the same input; values that pass only between
// stages (FramesDone) do not reach the client; an error thrown in on_value is an item error for
// that value and the session goes on.
class ProducerStage : public Stage {
 public:
  explicit ProducerStage(std::vector<std::string>& log) : log_(log) {}
  std::string_view name() const override { return "producer"; }
  std::string_view description() const override { return "test stage"; }
  std::vector<ValueKind> produces() const override { return {ValueKind::kFramesDone}; }
  void start(const v1::SessionHeader&, StageOutput&) override {}
  void on_camera_frame(const CameraFrame& camera, StageOutput& out) override {
    if (camera.depth_mm.empty()) return;
    log_.push_back("producer " + std::to_string(camera.t_us));
    out.hand_on(FramesDone{FrameSource::kForearm, camera.t_us});
  }
  void finish(StageOutput&) override { log_.push_back("producer finish"); }

 private:
  std::vector<std::string>& log_;
};

class ConsumerStage : public Stage {
 public:
  explicit ConsumerStage(std::vector<std::string>& log) : log_(log) {}
  std::string_view name() const override { return "consumer"; }
  std::string_view description() const override { return "test stage"; }
  std::vector<ValueKind> consumes() const override { return {ValueKind::kFramesDone}; }
  void start(const v1::SessionHeader&, StageOutput&) override {}
  void on_value(const StageValue& value, StageOutput&) override {
    const std::int64_t t = std::get<FramesDone>(value).up_to_t_us;
    log_.push_back("value " + std::to_string(t));
    if (t == throw_at_us) throw_invalid("consumer", "rejected by the test");
  }
  void on_camera_frame(const CameraFrame& camera, StageOutput&) override {
    if (!camera.depth_mm.empty()) log_.push_back("consumer " + std::to_string(camera.t_us));
  }
  void finish(StageOutput&) override { log_.push_back("consumer finish"); }
  std::int64_t throw_at_us = -1;

 private:
  std::vector<std::string>& log_;
};

TEST(SessionPipeline, AValueReachesTheLaterStagesWithinTheCallThatHandsItOn) {
  const auto chunks = demo::make_demo_session();
  std::vector<std::int64_t> depth_t_us;
  for (const auto& chunk : chunks) {
    if (chunk.has_depth()) depth_t_us.push_back(chunk.depth().t_us());
  }
  ASSERT_GE(depth_t_us.size(), 3u);
  std::vector<std::string> log;
  std::vector<std::unique_ptr<Stage>> stages;
  stages.push_back(std::make_unique<ProducerStage>(log));
  auto consumer = std::make_unique<ConsumerStage>(log);
  consumer->throw_at_us = depth_t_us[1];
  stages.push_back(std::move(consumer));
  CollectingSink sink;
  SessionPipeline pipeline(std::move(stages), sink);
  for (const auto& chunk : chunks) pipeline.push(chunk);
  pipeline.close();

  std::vector<std::string> expected;
  for (const std::int64_t t : depth_t_us) {
    for (const char* part : {"producer ", "value ", "consumer "}) expected.push_back(part + std::to_string(t));
  }
  expected.insert(expected.end(), {"producer finish", "consumer finish"});
  EXPECT_EQ(log, expected);
  EXPECT_TRUE(sink.of(v1::FitResult::kFrame).empty());  // FramesDone is for the stages only
  const auto errors = sink.item_errors();
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_EQ(errors[0].field(), "consumer");
  EXPECT_EQ(sink.results.back().summary().item_errors(), 1u);
}

TEST(SessionPipeline, ExtremeTimestampsAreRejectedAndTheStreamDurationStaysPositive) {
  CollectingSink reference;
  run(demo::make_demo_session(), reference);
  ASSERT_TRUE(reference.results.back().has_summary());
  const double full_duration_s = reference.results.back().summary().stream_duration_s();
  ASSERT_GT(full_duration_s, 0.0);

  // The first depth frame at INT64_MIN, the last at INT64_MAX: stream order is kept, but their
  // difference would overflow int64.
  auto chunks = demo::make_demo_session();
  const std::size_t first = index_of_nth(chunks, v1::SessionChunk::kDepth, 0);
  const std::size_t last = index_of_nth(chunks, v1::SessionChunk::kDepth, 299);
  chunks[first].mutable_depth()->set_t_us(std::numeric_limits<std::int64_t>::min());
  chunks[last].mutable_depth()->set_t_us(std::numeric_limits<std::int64_t>::max());
  CollectingSink sink;
  run(chunks, sink);

  const auto errors = sink.item_errors();
  ASSERT_GE(errors.size(), 2u);
  EXPECT_EQ(errors[0].field(), "chunk[" + std::to_string(first) + "].depth.t_us");
  EXPECT_EQ(errors[1].field(), "chunk[" + std::to_string(last) + "].depth.t_us");
  EXPECT_NE(errors[0].message().find("outside"), std::string::npos) << errors[0].message();
  ASSERT_TRUE(sink.results.back().has_summary());
  const v1::Summary& summary = sink.results.back().summary();
  EXPECT_EQ(summary.depth_frames(), 298u);
  // The rejected frames take no part: the duration is that of the chunks that were accepted.
  EXPECT_GT(summary.stream_duration_s(), 0.0);
  EXPECT_LE(summary.stream_duration_s(), full_duration_s);
}

}  // namespace
}  // namespace posefuse::session
