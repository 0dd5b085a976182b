// The body-fit stage on a short simulated camera session (core/sim/camera_session.hpp): the
// subject holds the controlled pose (arms 45 deg from the trunk) for the calibration frames and
// then raises the arms; the stage personalises, fits every frame and reports SMPL and camera
// joints. Degenerate inputs (no silhouette, no skeleton, bad options) become warnings or errors.
#include <gtest/gtest.h>

#include <limits>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <numbers>
#include <string>
#include <tuple>
#include <vector>

#include "body/smpl_model.hpp"
#include "common/error.hpp"
#include "raycast/depth_camera.hpp"
#include "session/frame_merge.hpp"
#include "session/pipeline.hpp"
#include "session/result_encoder.hpp"
#include "session/session_validator.hpp"
#include "session/stage_inputs.hpp"
#include "session/stages/body_fit_stage.hpp"
#include "session/stages/default_stages.hpp"
#include "session/text_fields.hpp"
#include "sim/camera_session.hpp"

namespace posefuse::session {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

struct Output : StageOutput {
  void emit(v1::FitResult&& result) override { results.push_back(std::move(result)); }
  // A fitted frame as the client gets it when only the fit estimated the frame (frame_merge.hpp).
  void hand_on(StageValue&& value) override {
    if (const auto* fitted = std::get_if<FittedFrame>(&value)) value = merge_fit_only(*fitted);
    if (std::optional<v1::FitResult> result = encode_value(value)) results.push_back(std::move(*result));
  }
  void warn(const std::string& code, const std::string& field, const std::string& message) override {
    v1::Warning w;
    w.set_code(code);
    w.set_field(field);
    w.set_message(message);
    warnings.push_back(w);
  }
  v1::CalibrationReport& calibration() override { return report; }

  std::vector<const v1::FrameResult*> frames() const {
    std::vector<const v1::FrameResult*> out;
    for (const auto& r : results) {
      if (r.has_frame()) out.push_back(&r.frame());
    }
    return out;
  }
  bool warned(const std::string& code, const std::string& field) const {
    for (const auto& w : warnings) {
      if (w.code() == code && w.field() == field) return true;
    }
    return false;
  }
  std::vector<v1::FitResult> results;
  std::vector<v1::Warning> warnings;
  v1::CalibrationReport report;
};

// The arms at first_angle_deg for 0.1 s, then rising by 30 deg over 0.1 s while the subject steps
// step_aside_m sideways.
sim::CameraSessionResult simulate(double duration_s, double first_angle_deg, double step_aside_m = 0.0) {
  sim::CameraSessionOptions options;
  options.duration_s = duration_s;
  options.betas = Eigen::VectorXd::Zero(10);
  options.betas << 0.8, -0.5, 0.4, 0, 0, 0, 0, 0, 0, 0;  // not the template's shape
  options.forearm_straps = {sim::ForearmStrap{sim::BodySide::kRight}, sim::ForearmStrap{sim::BodySide::kLeft}};
  const body::PoseLayout layout = body::PoseLayout::full_body();
  const int left = layout.index_of("left_shoulder_z"), right = layout.index_of("right_shoulder_z");
  const int aside = layout.index_of("translation_x");
  return sim::simulate_camera_session(options, layout, [=](double t_s) {
    Eigen::VectorXd theta = layout.zero();
    const double raise = t_s < 0.1 ? 0.0 : std::min(1.0, (t_s - 0.1) / 0.1);
    const double angle = (first_angle_deg + 30.0 * raise) * kDeg;  // 0 = arms horizontal
    theta[left] = angle;
    theta[right] = -angle;
    theta[aside] = step_aside_m * raise;
    return theta;
  });
}

// 0.1 s in the controlled pose (3 calibration frames at 30 Hz, arms 45 deg from the trunk), then
// the arms rise by 30 deg.
const sim::CameraSessionResult& session() {
  static const sim::CameraSessionResult result = simulate(0.2, -45.0);
  return result;
}

v1::SessionHeader header_with(std::map<std::string, std::string> options,
                              const sim::CameraSessionResult& from = session()) {
  v1::SessionHeader header = from.header;
  options.emplace("fit.enabled", "true");
  options.emplace("fit.calibration_s", "0.1");
  for (const auto& [key, value] : options) (*header.mutable_options())[key] = value;
  return header;
}

// The session's chunks that `keep` accepts, after `header`, as the pipeline hands them to a stage.
template <class Keep>
AssembledSession assemble(const v1::SessionHeader& header, Keep keep, const sim::CameraSessionResult& from) {
  std::vector<v1::SessionChunk> chunks(1);
  *chunks[0].mutable_header() = header;
  for (const auto& chunk : from.chunks) {
    if (keep(chunk)) chunks.push_back(chunk);
  }
  return assemble_session(chunks);
}
AssembledSession assemble(const v1::SessionHeader& header) {
  return assemble(
      header, [](const v1::SessionChunk&) { return true; }, session());
}

// Runs the stage over the session's chunks, keeping those `keep` accepts; `stats` receives the
// stage's per-frame statistics.
template <class Keep>
Output run(const v1::SessionHeader& header, Keep keep, const sim::CameraSessionResult& from = session(),
           std::vector<BodyFitFrameStats>* stats = nullptr) {
  Output out;
  BodyFitStage stage;
  stage.record_frame_stats(stats != nullptr);
  const AssembledSession inputs = assemble(header, keep, from);
  stage.start(header, out);
  for (const SessionInput& input : inputs.inputs) deliver_input(stage, input, out);
  stage.finish(out);
  if (stats) *stats = stage.frame_stats();
  if (!stats) {
    EXPECT_TRUE(stage.frame_stats().empty());  // not recorded unless asked
  }
  return out;
}

const auto kAllChunks = [](const v1::SessionChunk&) { return true; };

// With the default options, except that no frame's confidence is capped for its energy: a frame
// or two of this short session lies near fit.trusted_energy, above it under one compiler and not
// the other (FramesFittedAboveTheTrustedEnergyHaveLittleConfidence tests the cap).
const Output& full_run() {
  static const Output out =
      run(header_with({{"fit.trusted_energy", "100"}}), [](const v1::SessionChunk&) { return true; });
  return out;
}

Eigen::Vector3d vec(const v1::Vec3& v) { return {v.x(), v.y(), v.z()}; }

TEST(BodyFitStage, FitsEveryFrameCloseToTheTruth) {
  const Output& out = full_run();
  for (const auto& w : out.warnings) ADD_FAILURE() << w.code() << " " << w.field() << ": " << w.message();
  const auto frames = out.frames();
  const auto& truth = session().truth;
  ASSERT_EQ(frames.size(), truth.size());
  const int arm_joints[] = {body::kLeftShoulder, body::kRightShoulder, body::kLeftElbow,
                            body::kRightElbow,   body::kLeftWrist,     body::kRightWrist};
  double sum_fit = 0, sum_camera = 0, worst = 0;
  int n = 0;
  for (size_t i = 0; i < frames.size(); ++i) {
    const v1::FrameResult& f = *frames[i];
    EXPECT_EQ(f.t_us(), session().t_us[i]);
    ASSERT_EQ(f.smpl_joints_size(), body::kNumJoints);
    ASSERT_EQ(f.camera_joints_size(), 25);
    EXPECT_GT(f.fit_energy(), 0.0);
    for (const int j : arm_joints) {
      EXPECT_EQ(f.smpl_joints(j).source(), v1::VISUAL);  // no IMU in this session
      const double error = (vec(f.smpl_joints(j).position_m()) - truth[i].smpl_joints_K.col(j)).norm();
      sum_fit += error;
      worst = std::max(worst, error);
      ++n;
    }
    // The camera-compatible joints agree with the SMPL joints they sit on.
    EXPECT_LT((vec(f.camera_joints(5).position_m()) - vec(f.smpl_joints(body::kLeftElbow).position_m())).norm(), 1e-9);
  }
  // The camera skeleton's error for the same joints, for comparison.
  for (const auto& chunk : session().chunks) {
    if (!chunk.has_skeleton()) continue;
    const size_t i = static_cast<size_t>(
        std::find(session().t_us.begin(), session().t_us.end(), chunk.skeleton().t_us()) - session().t_us.begin());
    const int camera_of[] = {4, 8, 5, 9, 6, 10};
    for (int k = 0; k < 6; ++k) {
      sum_camera +=
          (vec(chunk.skeleton().joints(camera_of[k]).position_m()) - truth[i].smpl_joints_K.col(arm_joints[k])).norm();
    }
  }
  const double mean_fit = sum_fit / n, mean_camera = sum_camera / n;
  std::printf("body fit stage: shoulders/elbows/wrists mean %.1f mm (worst %.1f), camera skeleton %.1f mm\n",
              1e3 * mean_fit, 1e3 * worst, 1e3 * mean_camera);
  EXPECT_LT(mean_fit, 0.030);
  EXPECT_LT(worst, 0.060);
  EXPECT_LT(mean_fit, mean_camera);
}

TEST(BodyFitStage, RunsInTheDefaultPipelineWhenEnabled) {
  std::vector<v1::SessionChunk> chunks(1);
  *chunks[0].mutable_header() = header_with({});
  chunks.insert(chunks.end(), session().chunks.begin(), session().chunks.end());
  SessionValidator validator;
  for (const auto& chunk : chunks) validator.check(chunk);
  *chunks.emplace_back().mutable_end() = validator.counts();
  struct Sink : ResultSink {
    void emit(v1::FitResult&& result) override { results.push_back(std::move(result)); }
    std::vector<v1::FitResult> results;
  } sink;
  {
    SessionPipeline pipeline(make_default_stages(), sink);
    for (const auto& chunk : chunks) pipeline.push(chunk);
    pipeline.close();
  }
  size_t fitted = 0;
  const v1::Summary* summary = nullptr;
  std::int64_t last_frame_us = std::numeric_limits<std::int64_t>::min();
  for (const auto& r : sink.results) {
    fitted += r.has_frame() && r.frame().smpl_joints_size() == body::kNumJoints;
    // One FrameResult per frame (the frame merge), in time order.
    if (r.has_frame()) {
      EXPECT_GT(r.frame().t_us(), last_frame_us);
      last_frame_us = r.frame().t_us();
    }
    if (r.has_summary()) summary = &r.summary();
    EXPECT_FALSE(r.has_item_error()) << r.item_error().field() << ": " << r.item_error().message();
  }
  EXPECT_EQ(fitted, session().truth.size());
  ASSERT_NE(summary, nullptr);
  EXPECT_EQ(summary->frames_fitted(), session().truth.size());
}

// fit.calibration_s counts stream time, so a client that sends one camera frame again and again
// 10 us apart has every copy kept as a calibration frame. The session's memory budget ends it with
// RESOURCE_EXHAUSTED naming what holds the memory and the setting, once the frames held pass it.
TEST(SessionMemoryBudget, FramesFarCloserThanACameraSendsEndTheSessionNamingWhatHoldsThem) {
  const v1::SessionHeader header = header_with({{"fit.calibration_s", "30"}});
  std::vector<v1::SessionChunk> instant;  // the first depth frame's depth, body index and skeleton
  std::int64_t t0 = 0;
  for (const auto& chunk : session().chunks) {
    if (chunk.has_depth() && instant.empty()) t0 = chunk.depth().t_us();
    if (instant.empty() && !chunk.has_depth()) continue;
    const std::int64_t t = chunk.has_depth()        ? chunk.depth().t_us()
                           : chunk.has_body_index() ? chunk.body_index().t_us()
                           : chunk.has_skeleton()   ? chunk.skeleton().t_us()
                                                    : -1;
    if (t == t0) instant.push_back(chunk);
  }
  ASSERT_EQ(instant.size(), 3u);
  const std::size_t frame_bytes =
      static_cast<std::size_t>(header.depth_intrinsics().width()) * header.depth_intrinsics().height() * 3;
  constexpr std::uint64_t kBudget = 16 << 20;

  struct Sink : ResultSink {
    void emit(v1::FitResult&& result) override { results.push_back(std::move(result)); }
    std::vector<v1::FitResult> results;
  } sink;
  PipelineOptions options;
  options.max_held_bytes = kBudget;
  options.max_held_bytes_setting = "--test-budget";
  SessionPipeline pipeline(make_default_stages(), sink, options);
  v1::SessionChunk first;
  *first.mutable_header() = header;
  pipeline.push(first);
  std::optional<Error> ended;
  int frames_sent = 0;
  std::uint64_t held_before_last = 0;
  while (!ended && frames_sent < 1000) {
    held_before_last = pipeline.held_bytes();
    try {
      for (v1::SessionChunk chunk : instant) {
        const std::int64_t t = t0 + 10 * frames_sent;
        if (chunk.has_depth()) chunk.mutable_depth()->set_t_us(t);
        if (chunk.has_body_index()) chunk.mutable_body_index()->set_t_us(t);
        if (chunk.has_skeleton()) chunk.mutable_skeleton()->set_t_us(t);
        pipeline.push(chunk);
      }
    } catch (const Error& error) {
      ended = error;
    }
    ++frames_sent;
  }
  ASSERT_TRUE(ended) << "the budget never ended the session; held " << pipeline.held_bytes() << " bytes";
  EXPECT_EQ(ended->code(), ErrorCode::kResourceExhausted);
  const std::string message = ended->what();
  EXPECT_NE(message.find("body_fit"), std::string::npos) << message;
  EXPECT_NE(message.find("--test-budget"), std::string::npos) << message;
  EXPECT_NE(message.find("16.0 MiB"), std::string::npos) << message;
  EXPECT_EQ(message.find(" 0.0 MiB"), std::string::npos) << message;  // what holds next to nothing is left out
  // Ended by the frame that passed the budget: every frame before it was kept.
  EXPECT_LE(held_before_last, kBudget);
  EXPECT_GE(static_cast<std::size_t>(frames_sent), kBudget / frame_bytes);
  EXPECT_LE(static_cast<std::size_t>(frames_sent), kBudget / frame_bytes + 6);  // a few wait in the assembler
  for (const auto& r : sink.results) {
    EXPECT_FALSE(r.has_item_error()) << r.item_error().field() << ": " << r.item_error().message();
  }
}

// The forearm stage's per-sample K_from_F, here the truth, one sample per frame, handed on as the
// forearm stage hands them on: right, left; predicted errors as given (0: the truth).
void hand_truth_forearms(BodyFitStage& stage, StageOutput& out, double orientation_rms_rad = 0.0,
                         double axis_rms_rad = 0.0) {
  for (int strap = 0; strap < 2; ++strap) {
    ForearmOrientations batch;
    batch.arm = strap == 0 ? v1::RIGHT : v1::LEFT;
    for (size_t i = 0; i < session().truth.size(); ++i) {
      batch.t_us.push_back(session().t_us[i]);
      batch.K_from_F.push_back(session().truth[i].forearms[static_cast<size_t>(strap)].K_from_F);
      batch.pronation_rad.push_back(0.0);
      batch.orientation_rms_rad.push_back(orientation_rms_rad);
      batch.axis_rms_rad.push_back(axis_rms_rad);
    }
    stage.on_value(batch, out);
  }
}

TEST(BodyFitStage, ForearmOrientationsEnterTheFitAndTheResult) {
  Output out;
  BodyFitStage stage;
  const AssembledSession inputs = assemble(header_with({}));
  stage.start(header_with({}), out);
  hand_truth_forearms(stage, out);
  for (const SessionInput& input : inputs.inputs) deliver_input(stage, input, out);
  stage.finish(out);
  const auto frames = out.frames();
  ASSERT_EQ(frames.size(), session().truth.size());
  for (size_t i = 0; i < frames.size(); ++i) {
    const v1::FrameResult& f = *frames[i];
    EXPECT_EQ(f.smpl_joints(body::kRightWrist).source(), v1::FUSED);
    ASSERT_EQ(f.forearms_size(), 2);
    for (const auto& forearm : f.forearms()) {
      const bool is_left = forearm.arm() == v1::LEFT;
      const Eigen::Quaterniond got(forearm.k_from_f().w(), forearm.k_from_f().x(), forearm.k_from_f().y(),
                                   forearm.k_from_f().z());
      const Eigen::Quaterniond& want = session().truth[i].forearms[is_left ? 1 : 0].K_from_F;
      // The reported F's y lies on the fitted forearm; its roll is the IMU's.
      const Eigen::Vector3d axis = (vec(f.smpl_joints(is_left ? body::kLeftWrist : body::kRightWrist).position_m()) -
                                    vec(f.smpl_joints(is_left ? body::kLeftElbow : body::kRightElbow).position_m()))
                                       .normalized();
      EXPECT_LT(std::acos(std::min(1.0, (got * Eigen::Vector3d::UnitY()).dot(axis))), 1e-6);
      EXPECT_LT(got.angularDistance(want), 10 * kDeg) << "frame " << i << (is_left ? " left" : " right");
    }
  }
}

// The imu term uses the forearm axis y_F alone, so it is weighted by y_F's predicted error: a
// mounting from motion, whose roll is known to +-30 deg only, feeds it fully where its axis is
// known to a few degrees, and with less weight where it is known to 10 deg (the frames are FUSED,
// but the result reports no forearm turned from a K_from_F that is not confident); without a
// predicted error it does not enter.
TEST(BodyFitStage, TheForearmAxisEntersTheFitWhateverTheRollsError) {
  for (const double axis_deg : {3.0, 10.0, std::numeric_limits<double>::quiet_NaN()}) {
    SCOPED_TRACE("axis RMS " + std::to_string(axis_deg) + " deg");
    Output out;
    BodyFitStage stage;
    const AssembledSession inputs = assemble(header_with({}));
    stage.start(header_with({}), out);
    hand_truth_forearms(stage, out, 30 * kDeg, axis_deg * kDeg);
    for (const SessionInput& input : inputs.inputs) deliver_input(stage, input, out);
    stage.finish(out);
    const auto frames = out.frames();
    ASSERT_EQ(frames.size(), session().truth.size());
    for (const v1::FrameResult* f : frames) {
      for (const int wrist : {body::kLeftWrist, body::kRightWrist})
        EXPECT_EQ(f->smpl_joints(wrist).source(), std::isnan(axis_deg) ? v1::VISUAL : v1::FUSED);
      EXPECT_EQ(f->forearms_size(), axis_deg < 5 ? 2 : 0);
    }
  }
}

// posefuse-sim's chunk files order IMU batches by the device clock, 1-100 s ahead of the camera's,
// so in a short session every forearm orientation reaches the stage after the last camera frame.
// Frames wait for them up to fit.imu_wait_s (camera time); those that waited longer are fitted
// without the imu term, counted in FIT_NO_IMU.
TEST(BodyFitStage, FramesWaitForForearmOrientationsThatComeAfterThem) {
  v1::SessionHeader header = header_with({});
  for (const auto role : {v1::ImuDevice::ARM_LEFT, v1::ImuDevice::ARM_RIGHT}) {
    v1::ImuDevice& device = *header.add_imu_devices();
    device.set_device_id(role == v1::ImuDevice::ARM_LEFT ? "imu_left" : "imu_right");
    device.set_role(role);
    device.set_nominal_rate_hz(80);
  }
  for (const char* wait_s : {"30", "0.05"}) {
    SCOPED_TRACE(std::string("fit.imu_wait_s = ") + wait_s);
    (*header.mutable_options())["fit.imu_wait_s"] = wait_s;
    Output out;
    BodyFitStage stage;
    const AssembledSession inputs = assemble(header);
    stage.start(header, out);
    for (const SessionInput& input : inputs.inputs) deliver_input(stage, input, out);
    const size_t emitted_before_imu = out.frames().size();
    hand_truth_forearms(stage, out);
    stage.finish(out);
    const auto frames = out.frames();
    ASSERT_EQ(frames.size(), session().truth.size());
    size_t fused = 0;
    for (const v1::FrameResult* f : frames) fused += f->smpl_joints(body::kRightWrist).source() == v1::FUSED;
    if (std::string(wait_s) == "30") {
      EXPECT_EQ(emitted_before_imu, 0u);  // every frame waited
      EXPECT_EQ(fused, frames.size());
      EXPECT_FALSE(out.warned("FIT_NO_IMU", "fit"));
    } else {
      EXPECT_GT(emitted_before_imu, 0u);
      EXPECT_GT(fused, 0u);  // the frames still waiting when the orientations came
      ASSERT_LT(fused, frames.size());
      ASSERT_TRUE(out.warned("FIT_NO_IMU", "fit"));
      for (const auto& w : out.warnings) {
        if (w.code() == "FIT_NO_IMU") {
          EXPECT_EQ(
              w.message().rfind(std::to_string(frames.size() - fused) + " of " + std::to_string(frames.size()), 0), 0u)
              << w.message();
        }
      }
    }
  }
}

TEST(BodyFitStage, ReportsThePersonalisedShape) {
  const v1::BodyShape& shape = full_run().report.body_shape();
  EXPECT_TRUE(shape.estimated());
  EXPECT_EQ(shape.betas_size(), 10);
  EXPECT_EQ(shape.body_model(), header_with({}).sex() == v1::SessionHeader::FEMALE ? v1::BodyShape::TEMPLATE_FEMALE
                                                                                   : v1::BodyShape::TEMPLATE_MALE);
  EXPECT_GT(shape.upper_arm_length_left_m(), 0.2);
  EXPECT_LT(shape.upper_arm_length_left_m(), 0.4);
}

// The fine tuning (III-B) sets the betas no skeleton measurement sees (hip width, torso and limb
// girth: 6, 7, 8); the rough shape alone leaves them at 0.
TEST(BodyFitStage, FineShapeTuningSetsWhatTheSkeletonCannotSeeAndCanBeTurnedOff) {
  const v1::BodyShape& fine = full_run().report.body_shape();
  ASSERT_EQ(fine.betas_size(), 10);
  EXPECT_GT(std::abs(fine.betas(6)) + std::abs(fine.betas(7)) + std::abs(fine.betas(8)), 0.05);
  // The rough shape's fit reaches fit.trusted_energy in a frame (FIT_UNTRUSTED, tested on its own).
  const Output rough = run(header_with({{"fit.fine_shape", "false"}, {"fit.trusted_energy", "100"}}),
                           [](const v1::SessionChunk&) { return true; });
  for (const auto& w : rough.warnings) ADD_FAILURE() << w.code() << " " << w.field() << ": " << w.message();
  const v1::BodyShape& shape = rough.report.body_shape();
  EXPECT_TRUE(shape.estimated());
  ASSERT_EQ(shape.betas_size(), 10);
  for (int b : {6, 7, 8}) EXPECT_NEAR(shape.betas(b), 0.0, 1e-9) << "beta " << b;
}

TEST(BodyFitStage, OffWhenTheHeaderSaysSo) {
  v1::SessionHeader header = session().header;
  (*header.mutable_options())["fit.enabled"] = "false";
  const Output out = run(header, [](const v1::SessionChunk&) { return true; });
  EXPECT_TRUE(out.results.empty());
  EXPECT_TRUE(out.warnings.empty());
}

TEST(BodyFitStage, EmptySilhouetteIsAWarningPerFrame) {
  // Without body index maps every frame's silhouette is empty.
  const Output out = run(header_with({}), [](const v1::SessionChunk& c) { return !c.has_body_index(); });
  EXPECT_TRUE(out.frames().empty());
  EXPECT_TRUE(out.warned("FIT_FRAME", "frame.body_index"));
}

TEST(BodyFitStage, NoSkeletonIsAWarning) {
  const Output out = run(header_with({}), [](const v1::SessionChunk& c) { return !c.has_skeleton(); });
  EXPECT_TRUE(out.frames().empty());
  EXPECT_TRUE(out.warned("FIT_NO_SKELETON", "skeleton"));
}

// A camera wrist reported TRACKED half a metre from the body after the calibration frames (a
// camera off track, or a fit folded the wrong way: the frame cannot tell which): the fitted wrist
// takes an untracked wrist's confidence there and the session says how many frames.
TEST(BodyFitStage, AWristTheCameraTracksFarFromTheFitIsNotConfident) {
  sim::CameraSessionResult moved = session();
  const std::int64_t from_t_us = 100000;
  for (v1::SessionChunk& chunk : moved.chunks) {
    if (!chunk.has_skeleton() || chunk.skeleton().t_us() < from_t_us) continue;
    v1::Vec3& wrist = *chunk.mutable_skeleton()->mutable_joints(fit::kWristLeft)->mutable_position_m();
    wrist.set_x(wrist.x() + 0.5);
  }
  // Pulled by the far wrist, a frame's fit reaches fit.trusted_energy (tested on its own).
  const Output out = run(header_with({{"fit.trusted_energy", "100"}}, moved), kAllChunks, moved);
  ASSERT_FALSE(out.frames().empty());
  int far = 0;
  for (const v1::FrameResult* frame : out.frames()) {
    const double confidence = frame->smpl_joints(body::kLeftWrist).confidence();
    if (frame->t_us() < from_t_us) {
      EXPECT_EQ(confidence, 1.0) << frame->t_us();
    } else {
      EXPECT_EQ(confidence, 0.0) << frame->t_us();
      EXPECT_EQ(frame->smpl_joints(body::kRightWrist).confidence(), 1.0) << frame->t_us();
      ++far;
    }
  }
  EXPECT_GT(far, 0);
  EXPECT_TRUE(out.warned("FIT_OFF_CAMERA", "skeleton"));
}

// A subject who steps 1.6 m sideways leaves the depth image in part: every fitted joint that lies
// outside it has confidence 0, whatever the camera skeleton says, and the session says how many
// frames.
TEST(BodyFitStage, JointsOutsideTheDepthImageHaveNoConfidence) {
  const sim::CameraSessionResult aside = simulate(0.3, -45.0, 1.6);
  const Output out = run(header_with({{"fit.trusted_energy", "100"}}, aside), kAllChunks, aside);
  ASSERT_FALSE(out.frames().empty());
  const raycast::DepthCamera camera{sim::CameraSessionOptions{}.intrinsics};
  int outside = 0;
  for (const v1::FrameResult* frame : out.frames()) {
    for (const auto& joint : frame->camera_joints()) {
      const auto px = camera.project(vec(joint.position_m()));
      if (px && px->x() >= 0 && px->x() < camera.width() && px->y() >= 0 && px->y() < camera.height()) continue;
      EXPECT_EQ(joint.confidence(), 0.0) << frame->t_us();
      ++outside;
    }
  }
  EXPECT_GT(outside, 0);
  EXPECT_TRUE(out.warned("FIT_OUT_OF_VIEW", "fit"));
  EXPECT_FALSE(run(header_with({{"fit.trusted_energy", "100"}}), kAllChunks).warned("FIT_OUT_OF_VIEW", "fit"));
}

TEST(BodyFitStage, AnotherPersonsIdFitsNothing) {
  const Output out = run(header_with({{"fit.body_id", "3"}}), [](const v1::SessionChunk&) { return true; });
  EXPECT_TRUE(out.frames().empty());
  EXPECT_TRUE(out.warned("FIT_NO_SKELETON", "skeleton"));
}

TEST(BodyFitStage, OutOfTheControlledPoseFitsTheTemplateShape) {
  // Arms raised 135 deg from the trunk: personalisation refuses (fit/rough_shape.hpp), the stage
  // warns and still fits the frames with beta = 0.
  const sim::CameraSessionResult hanging = simulate(0.1, 45.0);
  const Output out = run(
      header_with({{"fit.calibration_s", "0.05"}}, hanging), [](const v1::SessionChunk&) { return true; }, hanging);
  bool warned = false;
  for (const auto& w : out.warnings) warned |= w.code() == "FIT_PERSONALISATION";
  EXPECT_TRUE(warned);
  EXPECT_EQ(out.frames().size(), hanging.truth.size());
  EXPECT_FALSE(out.report.body_shape().estimated());
  for (const double beta : out.report.body_shape().betas()) EXPECT_EQ(beta, 0.0);
}

TEST(BodyFitStage, BadOptionsAreErrors) {
  Output out;
  BodyFitStage stage;
  EXPECT_THROW(stage.start(header_with({{"fit.calibration_s", "-1"}}), out), Error);
  BodyFitStage other;
  EXPECT_THROW(other.start(header_with({{"fit.enabled", "yes"}}), out), Error);
  BodyFitStage third;
  EXPECT_THROW(third.start(header_with({{"fit.smoothing_frames", "2"}}), out), Error);
  BodyFitStage fourth;
  EXPECT_THROW(fourth.start(header_with({{"fit.fine_shape", "maybe"}}), out), Error);
  BodyFitStage fifth;
  EXPECT_THROW(fifth.start(header_with({{"fit.lambda_imu", "-1"}}), out), Error);
  for (const char* energy : {"-1", "nan", "inf", "x"}) {
    BodyFitStage stage_with;
    EXPECT_THROW(stage_with.start(header_with({{"fit.skeleton_start_energy", energy}}), out), Error) << energy;
  }
  for (const char* gain : {"-1", "nan", "x"}) {
    BodyFitStage stage_with;
    EXPECT_THROW(stage_with.start(header_with({{"fit.start_velocity_gain", gain}}), out), Error) << gain;
  }
  for (const char* after : {"-1", "x"}) {
    BodyFitStage stage_with;
    EXPECT_THROW(stage_with.start(header_with({{"fit.freeze_contour_after", after}}), out), Error) << after;
  }
  for (const char* project : {"yes", "on", ""}) {
    BodyFitStage stage_with;
    EXPECT_THROW(stage_with.start(header_with({{"fit.project_steps_onto_limits", project}}), out), Error) << project;
  }
  for (const char* damping : {"0", "-1", "nan", "inf", "x"}) {
    BodyFitStage stage_with;
    EXPECT_THROW(stage_with.start(header_with({{"fit.joint_step_stop_max_damping", damping}}), out), Error) << damping;
  }
  BodyFitStage valid;
  EXPECT_NO_THROW(valid.start(header_with({{"fit.start_velocity_gain", "1"},
                                           {"fit.freeze_contour_after", "0"},
                                           {"fit.joint_step_stop_max_damping", "1e8"}}),
                              out));
}

TEST(BodyFitStage, DurationOptionsHaveAnUpperBoundNamedInTheError) {
  // Both keep frames for as long as they say: without a bound, a header could make a session
  // hold every frame of the recording.
  struct Case {
    const char* key;
    const char* too_long;
    const char* longest;
  };
  for (const Case c : {Case{"fit.calibration_s", "30.5", "30"}, Case{"fit.imu_wait_s", "61", "60"},
                       Case{"fit.imu_wait_s", "1e300", "60"}}) {
    SCOPED_TRACE(std::string(c.key) + " = " + c.too_long);
    Output out;
    BodyFitStage stage;
    try {
      stage.start(header_with({{c.key, c.too_long}}), out);
      ADD_FAILURE() << "accepted";
    } catch (const Error& error) {
      EXPECT_EQ(error.field(), std::string("header.options[") + c.key + "]");
      EXPECT_NE(std::string(error.what()).find(std::string("(0, ") + c.longest + "]"), std::string::npos)
          << error.what();
    }
    BodyFitStage at_the_bound;
    EXPECT_NO_THROW(at_the_bound.start(header_with({{c.key, c.longest}}), out));
  }
}

TEST(BodyFitStage, SkeletonStartPolicyDecision) {
  EXPECT_TRUE(needs_skeleton_start(std::nullopt, 45));  // no previous frame: the skeleton start alone
  EXPECT_TRUE(needs_skeleton_start(45, 45));
  EXPECT_TRUE(needs_skeleton_start(1e6, 45));
  EXPECT_TRUE(needs_skeleton_start(std::nan(""), 45));
  EXPECT_FALSE(needs_skeleton_start(44.9, 45));
  EXPECT_TRUE(needs_skeleton_start(1.0, 0));  // policy off: always both
}

// Default policy: the skeleton start runs exactly where the policy asks for it, and the reported
// energy is the lower of the starts that ran.
TEST(BodyFitStage, SkeletonStartRunsOnlyWhenThePreviousFitIsNotGood) {
  for (const char* threshold : {"45", "2"}) {  // 2: below the session's energies (lowest 4.9), so both starts run
    std::vector<BodyFitFrameStats> stats;
    const Output out = run(header_with({{"fit.skeleton_start_energy", threshold}}), kAllChunks, session(), &stats);
    const auto frames = out.frames();
    ASSERT_EQ(stats.size(), frames.size());
    int skipped = 0;
    for (size_t i = 0; i < stats.size(); ++i) {
      const BodyFitFrameStats& f = stats[i];
      const bool had_previous = f.iterations_previous > 0;
      EXPECT_EQ(had_previous, i > 0) << "frame " << i;  // this session never loses tracking
      const bool expected = needs_skeleton_start(had_previous ? std::optional<double>(f.energy_previous) : std::nullopt,
                                                 std::stod(threshold));
      EXPECT_EQ(f.iterations_skeleton > 0, expected) << "frame " << i;
      skipped += !expected;
      const double lower =
          std::min(had_previous ? f.energy_previous : INFINITY, expected ? f.energy_skeleton : INFINITY);
      EXPECT_EQ(f.previous_won, had_previous && f.energy_previous == lower);
      EXPECT_GT(f.total_s(), 0.0);
    }
    double lowest = INFINITY;
    for (const auto& f : stats) lowest = std::min(lowest, f.previous_won ? f.energy_previous : f.energy_skeleton);
    std::printf("threshold %s: skeleton start skipped in %d of %zu frames (lowest energy %.2f)\n", threshold, skipped,
                stats.size(), lowest);
    if (std::string(threshold) == "2") {
      EXPECT_EQ(skipped, 0);
    }
  }
}

// Policy off: both starts on every frame, the skeleton start on a second thread; the lower
// energy is kept and each start's CPU time is reported.
// Lost tracking (energy above fit.lost_energy) is counted, and the next frame still starts from the
// lost frame's pose (the start policy adds the skeleton start after a poor fit). The threshold is
// set just below the session's highest frame energy, so that frame is lost: the fits are the same
// as without any lost frame.
TEST(BodyFitStage, LostTrackingIsCountedAndTheNextFrameStillStartsFromTheFittedPose) {
  std::vector<BodyFitFrameStats> first;
  run(header_with({}), kAllChunks, session(), &first);
  ASSERT_GE(first.size(), 3u);
  // A frame's energy is its winner's (a start that did not run has a NaN energy).
  const auto energy_of = [](const BodyFitFrameStats& f) {
    return f.previous_won ? f.energy_previous : f.energy_skeleton;
  };
  double highest = 0;
  for (const auto& f : first) highest = std::max(highest, energy_of(f));
  std::vector<BodyFitFrameStats> stats;
  const Output out =
      run(header_with({{"fit.lost_energy", format_double(0.999 * highest)}}), kAllChunks, session(), &stats);
  ASSERT_EQ(stats.size(), first.size());
  int lost = 0;
  for (size_t i = 0; i < stats.size(); ++i) {
    lost += energy_of(stats[i]) > 0.999 * highest;
    EXPECT_EQ(stats[i].iterations_previous > 0, i > 0) << "frame " << i;
    EXPECT_EQ(energy_of(stats[i]), energy_of(first[i])) << "frame " << i;
  }
  EXPECT_GE(lost, 1);
  ASSERT_TRUE(out.warned("FIT_LOST", "fit"));
  for (const auto& w : out.warnings) {
    if (w.code() == "FIT_LOST") {
      EXPECT_NE(w.message().find(" in " + std::to_string(lost) + " of " + std::to_string(stats.size()) + " frames"),
                std::string::npos)
          << w.message();
    }
  }
}

// A frame whose smoothing window (itself and its neighbours, fit.smoothing_frames 3) holds a fit
// above fit.trusted_energy keeps its pose, but its joints and forearms give at most the untrusted
// fit's confidence, and the session says how many frames. The threshold is set at the session's
// median frame energy, so about half the frames lie above it.
TEST(BodyFitStage, FramesFittedAboveTheTrustedEnergyHaveLittleConfidence) {
  const Output trusting = run(header_with({{"fit.trusted_energy", "100"}}), kAllChunks, session());
  const auto trusted_frames = trusting.frames();
  ASSERT_GE(trusted_frames.size(), 3u);
  std::vector<double> energies;
  for (const v1::FrameResult* frame : trusted_frames) energies.push_back(frame->fit_energy());
  std::nth_element(energies.begin(), energies.begin() + energies.size() / 2, energies.end());
  const double threshold = energies[energies.size() / 2];
  ASSERT_LT(threshold, 100.0);

  const Output out = run(header_with({{"fit.trusted_energy", format_double(threshold)}}), kAllChunks, session());
  const auto frames = out.frames();
  ASSERT_EQ(frames.size(), trusted_frames.size());
  // The smoother's window: centred, shrinking at the ends (the first and last frames alone).
  const auto window_above = [&](size_t i) {
    const size_t half = std::min({size_t{1}, i, frames.size() - 1 - i});
    bool above = false;
    for (size_t k = i - half; k <= i + half; ++k) above = above || frames[k]->fit_energy() > threshold;
    return above;
  };
  int untrusted = 0, capped_by_a_neighbour = 0;
  for (size_t i = 0; i < frames.size(); ++i) {
    const v1::FrameResult& frame = *frames[i];
    const v1::FrameResult& trusted = *trusted_frames[i];
    ASSERT_EQ(frame.fit_energy(), trusted.fit_energy()) << "frame " << i;
    const bool above = window_above(i);
    untrusted += above;
    capped_by_a_neighbour += above && frame.fit_energy() <= threshold;
    for (int j = 0; j < body::kNumJoints; ++j) {
      const double was = trusted.smpl_joints(j).confidence();
      EXPECT_EQ(frame.smpl_joints(j).position_m().x(), trusted.smpl_joints(j).position_m().x());
      EXPECT_EQ(frame.smpl_joints(j).confidence(), above ? std::min(was, fit::untrusted_fit_confidence()) : was)
          << "frame " << i << " joint " << j;
    }
    for (int f = 0; f < frame.forearms_size(); ++f) {
      EXPECT_LE(frame.forearms(f).confidence(), above ? fit::untrusted_fit_confidence() : 1.0) << "frame " << i;
    }
  }
  EXPECT_GE(untrusted, 1);
  EXPECT_GE(capped_by_a_neighbour, 1);
  EXPECT_FALSE(trusting.warned("FIT_UNTRUSTED", "fit"));
  ASSERT_TRUE(out.warned("FIT_UNTRUSTED", "fit"));
  for (const auto& w : out.warnings) {
    if (w.code() == "FIT_UNTRUSTED") {
      EXPECT_EQ(w.message().rfind(std::to_string(untrusted) + " of " + std::to_string(frames.size()) + " frames", 0),
                0u)
          << w.message();
      EXPECT_NE(w.message().find("confidence at most 0.0011"), std::string::npos) << w.message();
    }
  }
}

TEST(BodyFitStage, BothStartsRunOnTwoThreadsWhenThePolicyIsOff) {
  std::vector<BodyFitFrameStats> stats;
  // Both starts reach fit.trusted_energy in two frames (FIT_UNTRUSTED, tested on its own).
  const Output out = run(header_with({{"fit.skeleton_start_energy", "0"}, {"fit.trusted_energy", "100"}}), kAllChunks,
                         session(), &stats);
  for (const auto& w : out.warnings) ADD_FAILURE() << w.code() << " " << w.field() << ": " << w.message();
  ASSERT_EQ(stats.size(), out.frames().size());
  for (size_t i = 0; i < stats.size(); ++i) {
    const BodyFitFrameStats& f = stats[i];
    EXPECT_GT(f.iterations_skeleton, 0) << "frame " << i;
    EXPECT_GT(f.fit_skeleton_s, 0.0) << "frame " << i;
    if (i == 0) continue;
    EXPECT_GT(f.iterations_previous, 0) << "frame " << i;
    EXPECT_GT(f.fit_previous_s, 0.0) << "frame " << i;
    EXPECT_EQ(f.previous_won, f.energy_previous <= f.energy_skeleton) << "frame " << i;
    EXPECT_DOUBLE_EQ(out.frames()[i]->fit_energy(), std::min(f.energy_previous, f.energy_skeleton));
  }
}

TEST(BodyFitStage, SkeletonConversionKeepsPositionsAndTrackingStates) {
  Skeleton skeleton;
  skeleton.joints[geometry::kElbowLeft] = {geometry::Vec3(0.1, 0.2, 1.5), JointState::kInferred,
                                           geometry::Quat(0, 0, 0, 0)};
  skeleton.joints[geometry::kWristLeft] = {geometry::Vec3(0.3, 0.1, 1.4), JointState::kTracked,
                                           geometry::Quat::Identity()};
  const fit::TrackedSkeleton tracked = tracked_skeleton_from(skeleton);
  EXPECT_EQ(tracked.positions_K[geometry::kElbowLeft], geometry::Vec3(0.1, 0.2, 1.5));
  EXPECT_EQ(tracked.tracking[geometry::kElbowLeft], fit::JointTracking::kInferred);
  EXPECT_EQ(tracked.tracking[geometry::kWristLeft], fit::JointTracking::kTracked);
  EXPECT_EQ(tracked.tracking[geometry::kHead], fit::JointTracking::kNotTracked);
}

}  // namespace
}  // namespace posefuse::session
