// The demo path end to end, scored: a posefuse-sim session of paper 1's protocol (both arms)
// goes through SessionPipeline(make_default_stages()) in process, the results are written by the
// client's ResultWriter beside the simulator's gt/, and
// eval::score_directories (posefuse-score) compares the two. The bounds catch the frame
// convention and calibration bugs the demo had (docs/forearm.md "Scored against the
// simulator's truth").
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>

#include "../scratch_dir.hpp"
#include "client/result_writer.hpp"
#include "eval/result_score.hpp"
#include "session/pipeline.hpp"
#include "session/stages/default_stages.hpp"
#include "sim/ground_truth_files.hpp"
#include "sim/sim_session.hpp"
#include "tools/sim/sim_options_file.hpp"

using namespace posefuse;
namespace fs = std::filesystem;

namespace {

fs::path fresh_dir(const std::string& name) {
  return posefuse::testing::fresh_scratch_dir("posefuse_demo_score_test", name);
}

// The simulator's chunks straight into the pipeline.
class PipelineChunkSink : public session::ChunkSink {
 public:
  explicit PipelineChunkSink(session::SessionPipeline& pipeline) : pipeline_(pipeline) {}
  void write(const v1::SessionChunk& chunk) override { pipeline_.push(chunk); }
  void finish() override { pipeline_.close(); }

 private:
  session::SessionPipeline& pipeline_;
};

struct ScoredRun {
  fs::path results, gt;
  eval::ScoreReport report;
};

// Simulates `options_text` (posefuse-sim's options file syntax), runs the pipeline, scores.
ScoredRun simulate_run_and_score(const std::string& name, const std::string& options_text) {
  sim::SimSessionOptions options;
  tools::apply_sim_options(options_text, name, options);
  ScoredRun run;
  const fs::path dir = fresh_dir(name);
  run.results = dir / "results";
  run.gt = dir / "gt";
  {
    client::ResultWriter writer(run.results);
    client::ResultWriterSink results(writer);
    session::SessionPipeline pipeline(session::make_default_stages(), results);
    PipelineChunkSink chunks(pipeline);
    const sim::SimTruth truth = sim::simulate_session(options, chunks);
    chunks.finish();
    writer.finish();
    sim::write_ground_truth(truth, run.gt);
  }
  run.report = eval::score_directories(run.results, run.gt);
  std::cout << eval::format_score_report(run.report);
  return run;
}

}  // namespace

// Paper 1's protocol with both arms, 12 s (the calibration hold, behind the head, in front of
// the belly), seed 1, the simulator's default errors. Positions (branch fapos, left / right):
// d_sw off by 0.7 / 3.4 mm and d_se by 12.6 / 2.5 mm (the wrist where the hand begins; before,
// d_sw was 11.6 cm long), VISUAL 143 / 144 frames at 8.5 / 6.3 mm RMS (max 33 / 31 mm), the live
// estimate in gaps (PREDICTED) 56 / 80 mm RMS (max 111 / 103 mm), recovered SMOOTHER 14 / 12 mm
// RMS (max 20 / 17 mm); forearm orientation 3.5 / 6.3 deg RMS (max 5.5 / 9.1). Since branch
// forient (upper arm taper correction, still hold, SDK-elbow strap test): forearm orientation
// 3.50 / 5.26 deg RMS (max 5.54 / 7.99), VISUAL 143 / 143 frames at 7.9 / 6.7 mm. Earlier measured:
// forearm orientation RMS 10.1 / 13.4 deg (left / right; max 12.8 / 15.0), K_from_W 0.80 deg,
// r off by 1.9 / 2.5 mm, A_from_F 9.3 / 13.5 deg, strap positions (VISUAL) 17 / 72 mm RMS.
// Before the fixes: K_from_W 19.9 deg (base IMU's hard iron uncorrected), forearm RMS 32 / 60 deg;
// and in the demo (left arm at rest) the left forearm 133 deg RMS. The remaining ~10-13 deg are
// the calibration pose's roll about the forearm (docs/forearm.md), hence the bounds.
TEST(DemoScore, ProtocolWithBothArmsAgreesWithTheTruth) {
  const ScoredRun run = simulate_run_and_score("both_arms",
                                               "motion = forearm_protocol\n"
                                               "repetitions = 1\n"
                                               "arm = both\n"
                                               "duration_s = 12\n");
  const eval::ScoreReport& r = run.report;
  for (const char* device : {"imu_left", "imu_right", "imu_base"}) {
    const eval::AngleScore* imu = r.orientation(std::string("imu_orientations/") + device + ".csv", device);
    ASSERT_NE(imu, nullptr) << device;
    EXPECT_LT(imu->heading_deg.rms, 3.0) << device;  // measured 0.5-2.1
  }
  for (const char* device : {"imu_left", "imu_right"}) {
    const eval::AngleScore* forearm = r.orientation(std::string("forearm_orientations/") + device + ".csv", device);
    ASSERT_NE(forearm, nullptr) << device;
    EXPECT_GT(forearm->deg.count, 900u) << device;
    EXPECT_EQ(forearm->unmatched, 0u) << device;
    EXPECT_LT(forearm->deg.rms, 8.0) << device;   // measured 3.50 / 5.26 (3.5 / 6.3 before branch forient)
    EXPECT_LT(forearm->deg.max, 12.0) << device;  // measured 5.54 / 7.99 (5.5 / 9.1)
    const eval::PositionScore* visual = r.position(device, "VISUAL");
    ASSERT_NE(visual, nullptr) << device;
    EXPECT_GT(visual->m.count, 110u) << device;  // measured 143 / 144 (36 of the demo's 408 before)
    EXPECT_LT(visual->m.rms, 0.02) << device;    // measured 8.5 / 6.3 mm
    EXPECT_LT(visual->m.max, 0.05) << device;    // measured 33 / 31 mm (wrong bands accepted before: 0.34 m)
    const eval::PositionScore* predicted = r.position(device, "PREDICTED");
    ASSERT_NE(predicted, nullptr) << device;
    EXPECT_LT(predicted->m.rms, 0.12) << device;  // measured 56 / 80 mm (0.36-0.39 m in the demo before)
    EXPECT_LT(predicted->m.max, 0.16) << device;  // measured 111 / 103 mm
    const eval::PositionScore* smoother = r.position(device, "recovered SMOOTHER");
    ASSERT_NE(smoother, nullptr) << device;
    EXPECT_LT(smoother->m.rms, 0.03) << device;  // measured 14 / 12 mm
    EXPECT_LT(smoother->m.max, 0.05) << device;  // measured 20 / 17 mm
  }
  for (const char* arm : {"LEFT", "RIGHT"}) {
    const eval::AngleScore* per_frame = r.orientation("forearms.csv", arm);
    ASSERT_NE(per_frame, nullptr) << arm;
    EXPECT_LT(per_frame->deg.rms, 8.0) << arm;  // measured 3.51 / 5.27
    const std::string prefix = std::string(arm) + " ";
    ASSERT_NE(r.calibration_value(prefix + "r"), nullptr) << arm;
    EXPECT_LT(std::abs(r.calibration_value(prefix + "r")->error), 0.01) << arm;
    EXPECT_LT(r.calibration_value(prefix + "A_from_F")->error, 20.0) << arm;
    // d_ul is the SDK's shoulder to elbow: within 3 of its claimed sigmas (measured on seeds 1-6 of
    // this session: 0.5-8.3 cm off, sigma 6.1 cm).
    const eval::CalibrationScore* d_ul = r.calibration_value(prefix + "d_ul");
    EXPECT_GT(d_ul->uncertainty, 0.0) << arm;
    EXPECT_LT(std::abs(d_ul->error), 3.0 * d_ul->uncertainty) << arm;
    EXPECT_LT(std::abs(r.calibration_value(prefix + "d_sw")->error), 0.015) << arm;  // measured 0.7 / 3.4 mm
    EXPECT_LT(std::abs(r.calibration_value(prefix + "d_se")->error), 0.025) << arm;  // measured 12.6 / 2.5 mm
  }
  ASSERT_NE(r.calibration_value("K_from_W"), nullptr);
  EXPECT_LT(r.calibration_value("K_from_W")->error, 3.0);
  for (const char* device : {"imu_left", "imu_right", "imu_base"}) {
    const eval::CalibrationScore* clock = r.calibration_value(std::string("clock_offset ") + device);
    ASSERT_NE(clock, nullptr) << device;
    EXPECT_LT(std::abs(clock->error), 1000.0) << device;  // measured 117-344 us
  }
  ASSERT_NE(r.calibration_value("buzzer_tone"), nullptr);
  EXPECT_LT(std::abs(r.calibration_value("buzzer_tone")->error), 5.0);  // the tone measured in the audio
}

// The demo's former session: the protocol with the right arm, the left one resting at the side. The
// resting left arm is never in the calibration pose (it used to be calibrated from the resting
// pose and came out 133 deg off): its mounting comes from motion, and a forearm that never turns
// leaves the roll to the nominal mounting, so none of its samples is confident. The right arm is
// calibrated and scored.
TEST(DemoScore, RestingArmIsNotCalibratedAndNeverConfident) {
  const ScoredRun run = simulate_run_and_score("right_arm",
                                               "motion = forearm_protocol\n"
                                               "repetitions = 1\n"
                                               "arm = right\n"
                                               "duration_s = 6\n");
  const eval::ScoreReport& r = run.report;
  const eval::AngleScore* left = r.orientation("forearm_orientations/imu_left.csv", "imu_left");
  if (left) {  // orientations from motion, or none (FOREARM_MOUNTING_NOT_OBSERVABLE)
    EXPECT_GT(left->with_confidence, 0u);
    EXPECT_EQ(left->confident_deg.count, 0u);
    EXPECT_EQ(left->within_predicted_bound, left->with_uncertainty);
  }
  if (const eval::AngleScore* frames = r.orientation("forearms.csv", "LEFT")) {
    EXPECT_EQ(frames->confident_deg.count, 0u);
  }
  EXPECT_EQ(r.calibration_value("LEFT r"), nullptr);
  const eval::AngleScore* right = r.orientation("forearm_orientations/imu_right.csv", "imu_right");
  ASSERT_NE(right, nullptr);
  EXPECT_LT(right->deg.rms, 20.0);
  EXPECT_LT(r.calibration_value("K_from_W")->error, 3.0);
}

// The header names each arm IMU for the other arm (a clinic's mix-up). Eq. 9 would calibrate
// either IMU from the other arm's hold, and with both forearms vertical the camera check cannot
// see the mirrored roll (docs/benchmarks.md, "Adversarial sessions": up to 75 confident samples
// beyond 15 deg). The rise into the pose shows each IMU turning with the other forearm: both arms
// are named and get no results.
TEST(DemoScore, ImusOnTheWrongArmsAreNamedAndGiveNoResults) {
  const ScoredRun run = simulate_run_and_score("swapped",
                                               "motion = calibration_pose\n"
                                               "repetitions = 1\n"
                                               "arm = both\n"
                                               "duration_s = 7\n"
                                               "imu_roles_swapped = true\n");
  std::ifstream in(run.results / "warnings.txt");
  const std::string warnings((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const char* device : {"imu_left", "imu_right"}) {
    EXPECT_NE(warnings.find(std::string("FOREARM_IMU_ON_OTHER_ARM] forearm[") + device + "].arm"), std::string::npos)
        << warnings;
    EXPECT_EQ(run.report.orientation(std::string("forearm_orientations/") + device + ".csv", device), nullptr)
        << device;
  }
}
