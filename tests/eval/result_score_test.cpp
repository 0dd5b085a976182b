// posefuse-score's core on fixture directories written in code: known offsets between a result
// and a truth directory come back as the scored errors; mismatched times and missing files are
// clear errors.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>

#include "../imu/expect_error.hpp"
#include "common/error.hpp"
#include "eval/result_score.hpp"
#include "result_fixture.hpp"

using namespace posefuse;
using posefuse::result_fixture::FixtureSpec;

namespace {

using std::numbers::pi;

struct Pair {
  std::filesystem::path result, truth;
};

Pair write_pair(const std::string& name, const FixtureSpec& result, const FixtureSpec& truth) {
  Pair p{result_fixture::fresh_result_dir(name + "_result"), result_fixture::fresh_result_dir(name + "_gt")};
  result_fixture::write_fixture(p.result, result);
  result_fixture::write_fixture(p.truth, truth);
  return p;
}

}  // namespace

TEST(ResultScore, KnownOffsetsComeBackAsErrors) {
  FixtureSpec result, truth;
  result.forearm_angle_rad = 10.0 * pi / 180.0;
  result.position_offset_m = 0.02;
  result.r_m = 0.051;
  result.K_from_W_angle_rad = 20.0 * pi / 180.0;
  result.clock_offset_us = -1'000'150;
  result.buzzer_tone_hz = 2702.5;
  result.source = v1::FUSED;
  // Results 400 us late: still matched (tolerance 2 ms), and never to a neighbour.
  result.t0_us = 400;
  result.device_t0_us = truth.device_t0_us + 400;
  const Pair p = write_pair("known", result, truth);
  const eval::ScoreReport r = eval::score_directories(p.result, p.truth);

  for (const char* stream : {"forearm_orientations/imu_right.csv", "imu_orientations/imu_right.csv"}) {
    const eval::AngleScore* s = r.orientation(stream, "imu_right");
    ASSERT_NE(s, nullptr) << stream;
    EXPECT_EQ(s->unmatched, 0u);
    EXPECT_EQ(s->deg.count, 27u);  // 80 Hz over 10 frames at 30 Hz
    EXPECT_NEAR(s->deg.rms, 10.0, 1e-6);
    EXPECT_NEAR(s->deg.max, 10.0, 1e-6);
  }
  const eval::AngleScore* per_frame = r.orientation("forearms.csv", "RIGHT");
  ASSERT_NE(per_frame, nullptr);
  EXPECT_EQ(per_frame->deg.count, 10u);
  EXPECT_NEAR(per_frame->deg.rms, 10.0, 1e-6);

  for (const char* subset : {"all", "VISUAL", "PREDICTED"}) {
    const eval::PositionScore* s = r.position("imu_right", subset);
    ASSERT_NE(s, nullptr) << subset;
    EXPECT_NEAR(s->m.rms, 0.02, 1e-9) << subset;
    EXPECT_NEAR(s->m.max, 0.02, 1e-9) << subset;
  }
  EXPECT_EQ(r.position("imu_right", "VISUAL")->m.count, 5u);
  EXPECT_EQ(r.position("imu_right", "PREDICTED")->m.count, 5u);
  // The recovered trajectory is read at the truth's frame times: frames 6..9 lie inside the
  // segment (frame 5 is 400 us before its start), and the 400 us shift along a 0.11 m/s path
  // adds up to 44 um to the 2 cm offset.
  const eval::PositionScore* recovered = r.position("imu_right", "recovered SMOOTHER");
  ASSERT_NE(recovered, nullptr);
  EXPECT_EQ(recovered->m.count, 4u);
  EXPECT_NEAR(recovered->m.max, 0.02, 5e-5);

  ASSERT_EQ(r.joints.size(), 4u);
  for (const eval::JointGroupScore& g : r.joints) {
    EXPECT_EQ(g.stream, "camera_joints.csv");
    EXPECT_NEAR(g.mean_m, 0.02, 1e-9) << g.group;
  }
  EXPECT_NEAR(r.calibration_value("K_from_W")->error, 20.0, 1e-6);
  EXPECT_NEAR(r.calibration_value("RIGHT r")->error, 0.016, 1e-12);
  EXPECT_NEAR(r.calibration_value("RIGHT A_from_F")->error, 0.0, 1e-9);
  EXPECT_NEAR(r.calibration_value("clock_offset imu_right")->error, -150.0, 1e-9);
  EXPECT_NEAR(r.calibration_value("buzzer_tone")->error, 2.5, 1e-9);

  const std::string table = eval::format_score_report(r);
  EXPECT_NE(table.find("forearm_orientations/imu_right.csv  imu_right  27  10.00  10.00"), std::string::npos) << table;
  EXPECT_NE(table.find("K_from_W"), std::string::npos);
}

TEST(ResultScore, TheOfflineSolutionIsScoredAgainstTheLiveFoldersTruth) {
  FixtureSpec result, truth;
  result.forearm_angle_rad = 10.0 * pi / 180.0;
  const Pair p = write_pair("offline", result, truth);
  std::filesystem::copy(p.result / "forearm_orientations", p.result / "forearm_orientations_offline",
                        std::filesystem::copy_options::recursive);
  const eval::ScoreReport r = eval::score_directories(p.result, p.truth);
  const eval::AngleScore* offline = r.orientation("forearm_orientations_offline/imu_right.csv", "imu_right");
  ASSERT_NE(offline, nullptr);
  EXPECT_EQ(offline->deg.count, 27u);
  EXPECT_NEAR(offline->deg.rms, 10.0, 1e-6);
  // A truth without the live folder: the offline one has nothing to be scored against.
  std::filesystem::remove_all(p.result / "forearm_orientations");
  std::filesystem::remove_all(p.truth / "forearm_orientations");
  posefuse::testing::expect_error([&] { eval::score_directories(p.result, p.truth); }, ErrorCode::kNotFound,
                                  (p.truth / "forearm_orientations/imu_right.csv").string(),
                                  "missing in the truth directory");
}

TEST(ResultScore, RepetitionsOnAnotherDominantAngleAreScoredOnTheTruthsSeriesOfThatAngle) {
  FixtureSpec result, truth;
  truth.repetition_angle = v1::LEFT_ELBOW_FLEXION;
  const Pair p = write_pair("other_angle", result, truth);
  const eval::ScoreReport r = eval::score_directories(p.result, p.truth);
  ASSERT_TRUE(r.repetitions.has_value());
  EXPECT_EQ(r.repetitions->result_angle, "right_elbow_flexion");
  EXPECT_EQ(r.repetitions->truth_angle, "right_elbow_flexion");
  // The fixture's true right elbow flexion rises steadily: no repetition, where the truth's
  // left_elbow_flexion rows would have matched two.
  EXPECT_EQ(r.repetitions->truth_count, 0u);
  EXPECT_EQ(r.repetitions->matched, 0u);
  bool noted = false;
  for (const std::string& note : r.notes)
    noted = noted || note.find("dominant angle is left_elbow_flexion") != std::string::npos;
  EXPECT_TRUE(noted);
}

TEST(ResultScore, JointAnglesAndRepetitions) {
  FixtureSpec result, truth;
  result.angle_offset_deg = 3.0;
  result.right_pronation_defined = false;
  const Pair p = write_pair("angles", result, truth);
  const eval::ScoreReport r = eval::score_directories(p.result, p.truth);
  ASSERT_EQ(r.joint_angles.size(), 14u);  // left_plane_of_elevation is held in the truth: not scored
  for (const eval::JointAngleScore& s : r.joint_angles) {
    SCOPED_TRACE(s.angle);
    EXPECT_NE(s.angle, "left_plane_of_elevation");
    if (s.angle == "right_pronation") {
      EXPECT_EQ(s.deg.count, 0u);
      EXPECT_EQ(s.result_undefined, 10u);
      continue;
    }
    EXPECT_EQ(s.deg.count, 10u);
    EXPECT_NEAR(s.deg.rms, 3.0, 1e-9);
    EXPECT_NEAR(s.deg.max, 3.0, 1e-9);
    EXPECT_EQ(s.confident_deg.count, 10u);  // the fixture's result has confidence 1
    EXPECT_NEAR(s.confident_deg.rms, 3.0, 1e-9);
  }
  ASSERT_TRUE(r.repetitions.has_value());
  EXPECT_EQ(r.repetitions->result_count, 2u);  // the partial one is not counted
  EXPECT_EQ(r.repetitions->truth_count, 2u);
  EXPECT_EQ(r.repetitions->matched, 2u);
  EXPECT_NEAR(r.repetitions->range_deg.rms, 3.0, 1e-9);
  const std::string text = eval::format_score_report(r);
  EXPECT_NE(text.find("ISB joint angle error"), std::string::npos);
  EXPECT_NE(text.find("right_elbow_flexion"), std::string::npos);
}

TEST(ResultScore, IdenticalDirectoriesScoreZero) {
  const Pair p = write_pair("same", {}, {});
  const eval::ScoreReport r = eval::score_directories(p.result, p.truth);
  for (const auto& s : r.orientations) EXPECT_NEAR(s.deg.max, 0.0, 1e-6) << s.stream;
  for (const auto& s : r.positions) EXPECT_NEAR(s.m.max, 0.0, 1e-6) << s.subset;  // t_us in whole us
  EXPECT_TRUE(r.notes.empty());
}

TEST(ResultScore, RowsWithoutNearTruthAreCountedNotScored) {
  FixtureSpec result, truth;
  result.t0_us = 3000;  // camera-clock rows 3 ms late: beyond the 2 ms tolerance
  result.device_t0_us = truth.device_t0_us;
  const Pair p = write_pair("late", result, truth);
  posefuse::testing::expect_error([&] { eval::score_directories(p.result, p.truth); }, ErrorCode::kInvalidArgument,
                                  "forearm_orientations/imu_right.csv (imu_right)", "no t_us within 2000 us");
  eval::ScoreOptions wide;
  wide.tolerance_us = 5000;
  const eval::ScoreReport r = eval::score_directories(p.result, p.truth, wide);
  EXPECT_NEAR(r.orientation("forearms.csv", "RIGHT")->deg.max, 0.0, 1.0);  // 3 ms of a slow turn
}

TEST(ResultScore, MissingFilesAreClearErrors) {
  FixtureSpec truth;
  truth.with_segment = false;
  truth.with_joints = false;
  const Pair p = write_pair("missing", {}, truth);
  // A result stream without truth cannot be scored.
  posefuse::testing::expect_error([&] { eval::score_directories(p.result, p.truth); }, ErrorCode::kNotFound,
                                  (p.truth / "camera_joints.csv").string(), "missing in the truth directory");
  // The other way round a truth stream without results is a note.
  const eval::ScoreReport r = eval::score_directories(p.truth, p.result);
  ASSERT_FALSE(r.notes.empty());
  EXPECT_NE(r.notes.front().find("camera_joints.csv: not in the results"), std::string::npos) << r.notes.front();
  posefuse::testing::expect_error([&] { eval::score_directories(p.result / "nowhere", p.truth); }, ErrorCode::kNotFound,
                                  (p.result / "nowhere").string(), "not a directory");
  const auto empty = result_fixture::fresh_result_dir("empty");
  std::filesystem::create_directories(empty);
  posefuse::testing::expect_error([&] { eval::score_directories(empty, p.truth); }, ErrorCode::kNotFound,
                                  empty.string(), "none of the result files");
}

TEST(ResultScore, OccludedFramesFromTheTruthsOcclusionFile) {
  FixtureSpec result;
  result.position_offset_m = 0.01;
  const Pair p = write_pair("occluded", result, {});
  {
    std::ofstream occlusion(p.truth / "occlusion.csv");
    occlusion << "t_us,arm,forearm_visible_fraction,forearm_occluded,strap_visible\n";
    for (int f = 0; f < 10; ++f) {
      occlusion << static_cast<std::int64_t>(f / 30.0 * 1e6) << ",RIGHT,0.5," << (f >= 7 ? 1 : 0) << ",1\n";
    }
  }
  const eval::ScoreReport r = eval::score_directories(p.result, p.truth);
  const eval::PositionScore* occluded = r.position("imu_right", "occluded (gt)");
  ASSERT_NE(occluded, nullptr);
  EXPECT_EQ(occluded->m.count, 3u);
  EXPECT_NEAR(occluded->m.rms, 0.01, 1e-9);
  {
    std::ofstream bad(p.truth / "occlusion.csv", std::ios::app);
    bad << "0,RIGHT,0.5,yes,1\n";
  }
  posefuse::testing::expect_error([&] { eval::score_directories(p.result, p.truth); }, ErrorCode::kInvalidArgument,
                                  "occlusion.csv:12:forearm_occluded", "not 0 or 1");
}
