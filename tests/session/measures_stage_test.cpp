// The measures stage on frames whose angles are known: the angles handed on and encoded, the
// vertical from K_from_W (else assumed, with a warning), pronation from the frame's forearm
// orientation, the repetitions after the last frame, and a session without a body fit.
#include "session/stages/measures_stage.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "../measures/constructed_skeleton.hpp"
#include "../measures/floor_scene.hpp"
#include "collecting_output.hpp"
#include "common/error.hpp"

namespace posefuse::session {
namespace {

// The constructed subject's G (x front, y up, z right) for a subject facing a level camera:
// front = K's -z, right = K's x.
Eigen::Matrix3d facing_camera() {
  Eigen::Matrix3d K_from_G;
  K_from_G << 0, 0, 1, 0, 1, 0, -1, 0, 0;
  return K_from_G;
}

using measures::Angle;
using measures::testing::ArmPose;

// A frame with the right elbow at `elbow` deg, the camera tilted 10 deg (K_from_G) and the right
// forearm pronated 30 deg; exercise_frame: an elbow-flexion exercise, 20 + 80 (1 - cos) / 2 deg
// with period `period_s`.
FrameEstimate elbow_frame(double t_s, double elbow, const Eigen::Matrix3d& K_from_G) {
  const ArmPose right{30, 40, 10, elbow, 30, 0};
  const ArmPose left{0, 20, 0, 30, 0, 0};
  const measures::testing::Built b = measures::testing::build(K_from_G, 5, 0, 0, left, right);
  FrameEstimate frame;
  frame.t_us = std::llround(t_s * 1e6);
  for (int j = 0; j < 24; ++j) frame.smpl_joints.push_back({b.body.smpl_joints_K.col(j), v1::FUSED, 1.0});
  // K_from_F whose z (the right thumb axis) is the constructed thumb and y the forearm.
  const auto& J = b.body.smpl_joints_K;
  Eigen::Matrix3d K_from_F;
  K_from_F.col(1) = (J.col(21) - J.col(19)).normalized();
  K_from_F.col(2) = b.right_thumb_K.normalized();
  K_from_F.col(0) = K_from_F.col(1).cross(K_from_F.col(2));
  frame.forearms.push_back({v1::RIGHT, geometry::Quat(K_from_F), 0.0, v1::FUSED, 0.8});
  return frame;
}

FrameEstimate exercise_frame(double t_s, double period_s, const Eigen::Matrix3d& K_from_G) {
  return elbow_frame(t_s, 20 + 80 * (1 - std::cos(2 * std::numbers::pi * t_s / period_s)) / 2, K_from_G);
}

// A tracked arm IMU whose world z (up) is G's y: the stage takes its vertical from it.
ArmTrackStart arm_start_with_up(const Eigen::Vector3d& up_K) {
  ArmTrackStart start;
  start.tracked = true;
  start.K_from_W = geometry::Quat::FromTwoVectors(geometry::Vec3::UnitZ(), up_K);
  return start;
}

// Starts `stage` for a level camera facing the subject, its vertical from a tracked arm IMU, with
// measures.arm_length_uncertainty set where given ("0": the elbows' warning off).
void start_facing(MeasuresStage& stage, testing::CollectingOutput& out, const char* arm_length_uncertainty) {
  v1::SessionHeader header;
  if (arm_length_uncertainty) (*header.mutable_options())["measures.arm_length_uncertainty"] = arm_length_uncertainty;
  stage.start(header, out);
  stage.on_value(arm_start_with_up(facing_camera() * geometry::Vec3::UnitY()), out);
}

TEST(MeasuresStage, AnglesRepetitionsAndTheVertical) {
  const Eigen::Matrix3d K_from_G =
      Eigen::AngleAxisd(10 * std::numbers::pi / 180, Eigen::Vector3d::UnitX()).toRotationMatrix() * facing_camera();
  MeasuresStage stage;
  testing::CollectingOutput out;
  stage.start(v1::SessionHeader(), out);
  stage.on_value(arm_start_with_up(K_from_G * geometry::Vec3::UnitY()), out);
  const double period_s = 2.0;
  for (int f = 0; f < 30 * 9; ++f) stage.on_value(exercise_frame(f / 30.0, period_s, K_from_G), out);
  stage.finish(out);
  // The two warnings: elbows at 20-100 deg with the default arm length uncertainty
  // (ElbowFlexionConfidenceFollowsTheArmLengthUncertainty), and so repetitions of an angle that
  // is never confident (RepetitionsOnUnconfidentValuesAreCountedAndSaid).
  ASSERT_EQ(out.warnings.size(), 2u);
  EXPECT_EQ(out.warnings[0].rfind("MEASURES_ELBOW_FLEXION_UNCERTAIN", 0), 0u) << out.warnings[0];
  EXPECT_EQ(out.warnings[1].rfind("MEASURES_REPETITIONS_UNCERTAIN", 0), 0u) << out.warnings[1];

  int frames = 0;
  const v1::RepetitionSummary* summary = nullptr;
  for (const v1::FitResult& r : out.results) {
    if (r.has_joint_angles()) {
      ++frames;
      const v1::FrameAngles& a = r.joint_angles();
      ASSERT_EQ(a.angles_size(), measures::kAngleCount);
      EXPECT_EQ(a.angles(static_cast<int>(Angle::kRightElbowFlexion)).kind(), v1::RIGHT_ELBOW_FLEXION);
      EXPECT_NEAR(a.angles(static_cast<int>(Angle::kThoraxFlexion)).deg(), 5, 1e-6);
      EXPECT_NEAR(a.angles(static_cast<int>(Angle::kRightPlaneOfElevation)).deg(), 30, 1e-6);
      EXPECT_NEAR(a.angles(static_cast<int>(Angle::kRightElevation)).deg(), 40, 1e-6);
      const v1::JointAngle& pronation = a.angles(static_cast<int>(Angle::kRightPronation));
      EXPECT_TRUE(pronation.defined());
      EXPECT_NEAR(pronation.deg(), 30, 1e-6);
      EXPECT_DOUBLE_EQ(pronation.confidence(), 0.8);
      EXPECT_FALSE(a.angles(static_cast<int>(Angle::kLeftPronation)).defined());  // no left IMU
      EXPECT_EQ(a.angles(static_cast<int>(Angle::kRightElevation)).source(), v1::FUSED);
    }
    if (r.has_repetitions()) summary = &r.repetitions();
  }
  EXPECT_EQ(frames, 270);
  ASSERT_NE(summary, nullptr);
  EXPECT_EQ(summary->angle(), v1::RIGHT_ELBOW_FLEXION);
  EXPECT_TRUE(summary->angle_detected());
  EXPECT_EQ(summary->count(), 4u);  // 9 s of a 2 s period: four whole cycles and a partial one
  EXPECT_NEAR(summary->mean_range_deg(), 80, 0.5);
  EXPECT_NEAR(summary->mean_duration_s(), 2.0, 0.05);
}

TEST(MeasuresStage, ElbowFlexionConfidenceFollowsTheArmLengthUncertainty) {
  const auto run = [](const char* uncertainty) {
    MeasuresStage stage;
    testing::CollectingOutput out;
    start_facing(stage, out, uncertainty);
    for (int f = 0; f < 60; ++f) stage.on_value(exercise_frame(f / 30.0, 2, facing_camera()), out);
    stage.finish(out);
    return out;
  };
  // The left elbow holds 30 deg: with 5 % its flexion spreads about 12 deg, not confident.
  const testing::CollectingOutput uncertain = run(nullptr);
  ASSERT_EQ(uncertain.warnings.size(), 2u);  // and MEASURES_REPETITIONS_UNCERTAIN
  EXPECT_NE(uncertain.warnings[0].find("elbow flexion values are below confidence 0.5"), std::string::npos);
  EXPECT_LT(uncertain.results[0].joint_angles().angles(static_cast<int>(Angle::kLeftElbowFlexion)).confidence(), 0.5);
  // Known arm lengths: no warning, the elbows as confident as their joints.
  const testing::CollectingOutput exact = run("0");
  EXPECT_TRUE(exact.warnings.empty()) << exact.warnings.front();
  EXPECT_DOUBLE_EQ(exact.results[0].joint_angles().angles(static_cast<int>(Angle::kLeftElbowFlexion)).confidence(),
                   1.0);
  EXPECT_DOUBLE_EQ(exact.results[0].joint_angles().angles(static_cast<int>(Angle::kLeftElbowFlexion)).deg(),
                   uncertain.results[0].joint_angles().angles(static_cast<int>(Angle::kLeftElbowFlexion)).deg());
}

// An inferred thorax joint takes the elevations below 0.5 while no joint they are read from is:
// the stage says how many and why; with the thorax tracked it says nothing of them.
TEST(MeasuresStage, ElevationsUnconfidentForAnInferredThoraxAreSaid) {
  const auto run = [](double spine2_confidence) {
    MeasuresStage stage;
    testing::CollectingOutput out;
    start_facing(stage, out, "0");
    for (int f = 0; f < 60; ++f) {
      FrameEstimate frame = exercise_frame(f / 30.0, 2, facing_camera());
      if (f % 2 == 0) frame.smpl_joints[6].confidence = spine2_confidence;
      stage.on_value(frame, out);
    }
    stage.finish(out);
    return out;
  };
  const testing::CollectingOutput inferred = run(0.5);
  const auto warned = [](const testing::CollectingOutput& out) {
    return std::find_if(out.warnings.begin(), out.warnings.end(),
                        [](const std::string& w) { return w.rfind("MEASURES_ELEVATION_UNCERTAIN", 0) == 0; });
  };
  ASSERT_NE(warned(inferred), inferred.warnings.end());
  EXPECT_NE(warned(inferred)->find("60 of 120 elevation values"), std::string::npos) << *warned(inferred);
  EXPECT_LT(inferred.results[0].joint_angles().angles(static_cast<int>(Angle::kRightElevation)).confidence(), 0.5);
  EXPECT_GE(inferred.results[1].joint_angles().angles(static_cast<int>(Angle::kRightElevation)).confidence(), 0.5);
  const testing::CollectingOutput tracked = run(1.0);
  EXPECT_EQ(warned(tracked), tracked.warnings.end());
  // Untracked (0): the joint itself says so; nothing to add.
  const testing::CollectingOutput lost = run(0.0);
  EXPECT_EQ(warned(lost), lost.warnings.end());
}

// A trunk tilted 60 deg to the side takes the thorax flexion below 0.5 while its joints and the
// vertical are confident (Z-X-Y near its gimbal lock): the stage says how many and why.
TEST(MeasuresStage, ThoraxValuesUnconfidentForATiltedTrunkAreSaid) {
  MeasuresStage stage;
  testing::CollectingOutput out;
  start_facing(stage, out, "0");
  for (int f = 0; f < 60; ++f) {
    const double tilt_deg = f % 3 == 0 ? 60 : 10;
    const measures::testing::Built b = measures::testing::build(
        facing_camera(), 5, tilt_deg, 0, ArmPose{0, 20, 0, 30, 0, 0}, ArmPose{30, 40, 10, 60, 0, 0});
    FrameEstimate frame;
    frame.t_us = std::llround(f / 30.0 * 1e6);
    for (int j = 0; j < 24; ++j) frame.smpl_joints.push_back({b.body.smpl_joints_K.col(j), v1::FUSED, 1.0});
    stage.on_value(frame, out);
  }
  stage.finish(out);
  const auto warned = std::find_if(out.warnings.begin(), out.warnings.end(),
                                   [](const std::string& w) { return w.rfind("MEASURES_THORAX_TILTED", 0) == 0; });
  ASSERT_NE(warned, out.warnings.end());
  EXPECT_NE(warned->find("20 of 60 frames have their thorax flexion"), std::string::npos) << *warned;
  const auto flexion = [&](int f) {
    return out.results[static_cast<size_t>(f)].joint_angles().angles(static_cast<int>(Angle::kThoraxFlexion));
  };
  EXPECT_NEAR(flexion(0).deg(), 5, 1e-6);
  EXPECT_LT(flexion(0).confidence(), 0.5);
  EXPECT_GE(flexion(1).confidence(), 0.5);
  EXPECT_GE(out.results[0].joint_angles().angles(static_cast<int>(Angle::kThoraxLateralTilt)).confidence(), 0.5);
}

// Repetitions segmented on values not to act on are still reported, and the result says so: with
// every joint untracked (confidence 0) the elbow's repetitions count as before, with confidence 0,
// and warning MEASURES_REPETITIONS_UNCERTAIN; with exact arm lengths and tracked joints nothing is
// said and every range is confident.
TEST(MeasuresStage, RepetitionsOnUnconfidentValuesAreCountedAndSaid) {
  const auto run = [](double joint_confidence) {
    MeasuresStage stage;
    testing::CollectingOutput out;
    v1::SessionHeader header;
    (*header.mutable_options())["measures.arm_length_uncertainty"] = "0";
    stage.start(header, out);
    stage.on_value(arm_start_with_up(facing_camera() * geometry::Vec3::UnitY()), out);
    for (int f = 0; f < 30 * 9; ++f) {
      FrameEstimate frame = exercise_frame(f / 30.0, 2, facing_camera());
      for (JointEstimate& j : frame.smpl_joints) j.confidence = joint_confidence;
      stage.on_value(frame, out);
    }
    stage.finish(out);
    return out;
  };
  const auto summary_of = [](const testing::CollectingOutput& out) {
    for (const v1::FitResult& r : out.results)
      if (r.has_repetitions()) return r.repetitions();
    ADD_FAILURE() << "no repetitions";
    return v1::RepetitionSummary();
  };
  const testing::CollectingOutput untracked = run(0.0);
  const v1::RepetitionSummary unsure = summary_of(untracked);
  EXPECT_EQ(unsure.angle(), v1::RIGHT_ELBOW_FLEXION);
  EXPECT_EQ(unsure.count(), 4u);
  EXPECT_DOUBLE_EQ(unsure.confident_fraction(), 0.0);
  EXPECT_EQ(unsure.uncertain_count(), 4u);
  for (const v1::Repetition& rep : unsure.repetitions()) EXPECT_DOUBLE_EQ(rep.confidence(), 0.0);
  ASSERT_EQ(untracked.warnings.size(), 1u);
  EXPECT_EQ(untracked.warnings[0].rfind("MEASURES_REPETITIONS_UNCERTAIN", 0), 0u) << untracked.warnings[0];
  EXPECT_NE(untracked.warnings[0].find("only 0 % of right_elbow_flexion's defined frames"), std::string::npos)
      << untracked.warnings[0];

  const testing::CollectingOutput tracked = run(1.0);
  EXPECT_TRUE(tracked.warnings.empty()) << tracked.warnings.front();
  const v1::RepetitionSummary sure = summary_of(tracked);
  EXPECT_EQ(sure.count(), 4u);
  EXPECT_DOUBLE_EQ(sure.confident_fraction(), 1.0);
  EXPECT_EQ(sure.uncertain_count(), 0u);
  for (const v1::Repetition& rep : sure.repetitions()) EXPECT_DOUBLE_EQ(rep.confidence(), 1.0);
}

TEST(MeasuresStage, WithoutKFromWTheVerticalIsAssumedAndSaid) {
  MeasuresStage stage;
  testing::CollectingOutput out;
  stage.start(v1::SessionHeader(), out);
  stage.on_value(exercise_frame(0, 2, facing_camera()), out);
  ASSERT_EQ(out.warnings.size(), 1u);
  EXPECT_EQ(out.warnings[0].rfind("MEASURES_VERTICAL_ASSUMED", 0), 0u);
  ASSERT_FALSE(out.results.empty());
  const v1::FrameAngles& a = out.results[0].joint_angles();
  EXPECT_DOUBLE_EQ(a.angles(static_cast<int>(Angle::kThoraxFlexion)).confidence(), 0.5);
  EXPECT_NEAR(a.angles(static_cast<int>(Angle::kThoraxFlexion)).deg(), 5, 1e-6);
}

// A trunk tilting right, left and back three times, the arms still. With `settling_start` the
// series starts 10 deg to the left and settles upright before the first tilt, which goes right:
// the segmenter cannot tell that from a tilt under way (docs/measures.md, "Angles that swing
// about their zero"), counts one fewer and says so; started upright, it counts all three.
std::vector<FrameEstimate> tilt_session(bool settling_start) {
  std::vector<FrameEstimate> frames;
  const auto tilt_at = [&](double t_s) {
    const auto ramp = [](double from, double to, double phase) {
      return from + (to - from) * (1 - std::cos(std::numbers::pi * std::clamp(phase, 0.0, 1.0))) / 2;
    };
    if (t_s < 1.5) return settling_start ? ramp(-10, 0, t_s / 0.5) : 0.0;
    const double c = std::fmod(t_s - 1.5, 5.0);  // right 1.5 s, left 2 s, upright 1 s, hold 0.5 s
    if (c < 1.5) return ramp(0, 20, c / 1.5);
    if (c < 3.5) return ramp(20, -20, (c - 1.5) / 2.0);
    return ramp(-20, 0, (c - 3.5) / 1.0);
  };
  for (int f = 0; f < 30 * 17; ++f) {
    const double t_s = f / 30.0;
    const ArmPose arm{0, 20, 0, 90, 0, 0};
    const measures::testing::Built b = measures::testing::build(facing_camera(), 0, tilt_at(t_s), 0, arm, arm);
    FrameEstimate frame;
    frame.t_us = std::llround(t_s * 1e6);
    for (int j = 0; j < 24; ++j) frame.smpl_joints.push_back({b.body.smpl_joints_K.col(j), v1::FUSED, 1.0});
    frames.push_back(frame);
  }
  return frames;
}

TEST(MeasuresStage, AStartThatMayHoldARepetitionIsSaid) {
  for (const bool settling_start : {true, false}) {
    SCOPED_TRACE(settling_start ? "settling start" : "upright start");
    MeasuresStage stage;
    testing::CollectingOutput out;
    stage.start(v1::SessionHeader(), out);
    stage.on_value(arm_start_with_up(geometry::Vec3::UnitY()), out);
    for (const FrameEstimate& frame : tilt_session(settling_start)) stage.on_value(frame, out);
    stage.finish(out);
    const v1::FitResult& last = out.results.back();
    ASSERT_TRUE(last.has_repetitions());
    const v1::RepetitionSummary& summary = last.repetitions();
    EXPECT_EQ(summary.angle(), v1::THORAX_LATERAL_TILT);
    EXPECT_EQ(summary.count(), settling_start ? 2u : 3u);
    ASSERT_FALSE(summary.repetitions().empty());
    EXPECT_EQ(summary.repetitions(0).may_hold_repetition(), settling_start);
    int said = 0;
    for (const std::string& w : out.warnings) said += w.rfind("MEASURES_START_AMBIGUOUS", 0) == 0;
    EXPECT_EQ(said, settling_start ? 1 : 0);
  }
}

// Reaches from a hold half way: the elbow rests at 20, reaches 160 and holds at 92 or 88 between
// reaches, 2 deg from the middle of its range (90). The session says that those turns may or
// may not end repetitions; with the hold at 50 it says nothing. Held at 92 the holds end none
// (one repetition); held at 88 they end repetitions, and the reach between two of them, whose
// range would be the whole excursion were they read the other way, has an unconfident range,
// which the session says too (exact arm lengths: every sample is confident).
TEST(MeasuresStage, TurnsNearTheMiddleOfTheRangeAreSaid) {
  for (const double hold_deg : {92.0, 88.0, 50.0}) {
    SCOPED_TRACE("hold at " + std::to_string(hold_deg));
    v1::SessionHeader header;
    (*header.mutable_options())["measures.repetition_angle"] = "right_elbow_flexion";
    (*header.mutable_options())["measures.arm_length_uncertainty"] = "0";
    MeasuresStage stage;
    testing::CollectingOutput out;
    stage.start(header, out);
    std::vector<std::pair<double, double>> path = {{0, 20}, {1, 20}};  // (s, deg), linear between
    for (int r = 0; r < 3; ++r) {
      const double t = path.back().first;
      path.insert(path.end(), {{t + 1, 160}, {t + 1.5, 160}, {t + 2.5, hold_deg}, {t + 3, hold_deg}});
    }
    path.insert(path.end(), {{path.back().first + 1, 20}, {path.back().first + 2, 20}});
    for (int f = 0; f / 30.0 <= path.back().first; ++f) {
      const double t = f / 30.0;
      std::size_t i = 1;
      while (path[i].first < t) ++i;
      const double u = (t - path[i - 1].first) / (path[i].first - path[i - 1].first);
      stage.on_value(elbow_frame(t, path[i - 1].second + u * (path[i].second - path[i - 1].second), facing_camera()),
                     out);
    }
    stage.finish(out);
    int said = 0, range_said = 0;
    for (const std::string& w : out.warnings) {
      said += w.rfind("MEASURES_REST_AMBIGUOUS", 0) == 0;
      range_said += w.rfind("MEASURES_REPETITION_RANGE_UNCERTAIN", 0) == 0;
    }
    EXPECT_EQ(said, hold_deg == 50.0 ? 0 : 1);
    ASSERT_TRUE(out.results.back().has_repetitions());
    const v1::RepetitionSummary& summary = out.results.back().repetitions();
    EXPECT_EQ(summary.count(), hold_deg == 92.0 ? 1u : 3u);
    EXPECT_EQ(summary.uncertain_count(), hold_deg == 88.0 ? 1u : 0u);
    EXPECT_EQ(range_said, hold_deg == 88.0 ? 1 : 0);
    // The result carries how far the cut may move each range: the reach between the holds
    // (88 -> 160) would run from the rest at 20.
    double largest_cut_deg = 0;
    for (const v1::Repetition& rep : summary.repetitions())
      if (!rep.partial()) largest_cut_deg = std::max(largest_cut_deg, rep.cut_ambiguity_deg());
    EXPECT_NEAR(largest_cut_deg, hold_deg == 88.0 ? 160 - 20 - (160 - 88) : 0, 0.5);
  }
}

// A camera pitched 10 deg down whose depth frame shows the floor: the thorax angles are read
// against the floor's up, not the camera's y (which would turn the trunk's 5 deg of flexion into
// 15), at the floor's confidence, and the calibration report says how the camera stands. A frame
// without depth leaves the vertical assumed.
TEST(MeasuresStage, TheVerticalComesFromTheFloorWhenTheDepthShowsOne) {
  const measures::testing::Room room = measures::testing::room(10, 0);
  const Eigen::Matrix3d K_from_G =
      Eigen::AngleAxisd(-10 * std::numbers::pi / 180, Eigen::Vector3d::UnitX()).toRotationMatrix() * facing_camera();
  v1::SessionHeader header;
  const geometry::PinholeCamera camera;
  *header.mutable_depth_intrinsics() = camera_intrinsics(camera);
  const measures::testing::Frame depth = measures::testing::render(camera, room.planes);
  for (const bool with_depth : {true, false}) {
    SCOPED_TRACE(with_depth ? "with depth" : "without depth");
    MeasuresStage stage;
    testing::CollectingOutput out;
    stage.start(header, out);
    CameraFrame frame;
    if (with_depth) {
      frame.depth_mm =
          cv::Mat(camera.height, camera.width, CV_16UC1, const_cast<std::uint16_t*>(depth.depth_mm.data()));
      frame.body_index =
          cv::Mat(camera.height, camera.width, CV_8UC1, const_cast<std::uint8_t*>(depth.body_index.data()));
    }
    stage.on_camera_frame(frame, out);
    stage.on_value(exercise_frame(0, 2, K_from_G), out);
    stage.finish(out);
    ASSERT_FALSE(out.results.empty());
    const v1::JointAngle& flexion = out.results[0].joint_angles().angles(static_cast<int>(Angle::kThoraxFlexion));
    bool assumed = false;
    for (const std::string& w : out.warnings) assumed |= w.rfind("MEASURES_VERTICAL_ASSUMED", 0) == 0;
    const v1::CameraVertical& vertical = out.report.vertical();
    if (with_depth) {
      EXPECT_NEAR(flexion.deg(), 5, 0.3);
      // The floor's (above 0.99) leaves the thorax's own spread the smaller (measures::joint_angles).
      EXPECT_GT(flexion.confidence(), 0.6);
      EXPECT_FALSE(assumed);
      EXPECT_EQ(vertical.source(), v1::CameraVertical::FLOOR);
      EXPECT_NEAR(vertical.camera_pitch_deg(), 10, 0.3);
      EXPECT_NEAR(vertical.camera_roll_deg(), 0, 0.3);
      EXPECT_NEAR(vertical.camera_height_m(), 1.0, 0.01);
      EXPECT_GT(vertical.floor_points(), 200u);
      EXPECT_DOUBLE_EQ(vertical.floor_imu_angle_deg(), -1);
    } else {
      EXPECT_NEAR(flexion.deg(), 15, 0.3);
      EXPECT_DOUBLE_EQ(flexion.confidence(), 0.5);
      EXPECT_TRUE(assumed);
      EXPECT_EQ(vertical.source(), v1::CameraVertical::ASSUMED);
      EXPECT_NEAR(vertical.camera_pitch_deg(), 0, 1e-9);
    }
  }
}

TEST(MeasuresStage, NamedAngleAndNoBodyFit) {
  MeasuresStage stage;
  testing::CollectingOutput out;
  v1::SessionHeader header;
  (*header.mutable_options())["measures.repetition_angle"] = "left_elevation";
  stage.start(header, out);
  for (int f = 0; f < 60; ++f) stage.on_value(exercise_frame(f / 30.0, 2, facing_camera()), out);
  stage.finish(out);
  const v1::FitResult& last = out.results.back();
  ASSERT_TRUE(last.has_repetitions());
  EXPECT_EQ(last.repetitions().angle(), v1::LEFT_ELEVATION);
  EXPECT_FALSE(last.repetitions().angle_detected());
  EXPECT_EQ(last.repetitions().count(), 0u);  // the left arm holds still

  // Without a fitted frame: no angles; a warning only where the fit was asked for.
  for (const bool fit_on : {false, true}) {
    MeasuresStage no_fit;
    testing::CollectingOutput none;
    v1::SessionHeader fit_header;
    (*fit_header.mutable_options())["fit.enabled"] = fit_on ? "true" : "false";
    no_fit.start(fit_header, none);
    FrameEstimate camera_only;
    camera_only.t_us = 1000;
    no_fit.on_value(camera_only, none);
    no_fit.finish(none);
    EXPECT_TRUE(none.results.empty());
    ASSERT_EQ(none.warnings.size(), fit_on ? 1u : 0u);
    if (fit_on) {
      EXPECT_EQ(none.warnings[0].rfind("MEASURES_NO_BODY_FIT", 0), 0u);
    }
  }
}

TEST(MeasuresStage, DegenerateJointsSkipTheFrameNotTheSession) {
  MeasuresStage stage;
  testing::CollectingOutput out;
  stage.start(v1::SessionHeader(), out);
  FrameEstimate collapsed = exercise_frame(0, 2, facing_camera());
  for (JointEstimate& j : collapsed.smpl_joints) j.p_K = geometry::Vec3(0, 0, 2);  // no thorax frame
  for (int f = 0; f < 3; ++f) {
    collapsed.t_us = f * 33'333;
    EXPECT_NO_THROW(stage.on_value(collapsed, out));
  }
  stage.on_value(exercise_frame(0.1, 2, facing_camera()), out);
  stage.finish(out);
  int angle_frames = 0;
  for (const v1::FitResult& r : out.results) angle_frames += r.has_joint_angles();
  EXPECT_EQ(angle_frames, 1);
  bool counted = false;
  for (const std::string& w : out.warnings)
    counted |= w.rfind("MEASURES_FRAME_SKIPPED", 0) == 0 && w.find("3 fitted frames") != std::string::npos;
  EXPECT_TRUE(counted);
}

TEST(MeasuresStage, BadOptionsNameTheOption) {
  const auto field_of = [](const std::map<std::string, std::string>& options) {
    v1::SessionHeader header;
    for (const auto& [k, v] : options) (*header.mutable_options())[k] = v;
    MeasuresStage stage;
    testing::CollectingOutput out;
    try {
      stage.start(header, out);
    } catch (const Error& e) {
      return e.field();
    }
    return std::string("accepted");
  };
  EXPECT_EQ(field_of({{"measures.repetition_angle", "left_knee"}}), "header.options[measures.repetition_angle]");
  EXPECT_EQ(field_of({{"measures.hysteresis_deg", "-1"}}), "header.options[measures.hysteresis_deg]");
  EXPECT_EQ(field_of({{"measures.hysteresis_deg", "30"}}), "header.options[measures.min_amplitude_deg]");
  EXPECT_EQ(field_of({{"measures.min_repetition_s", "40"}}), "header.options[measures.max_repetition_s]");
  EXPECT_EQ(field_of({{"measures.min_elbow_flexion_deg", "90"}}), "header.options[measures.min_elbow_flexion_deg]");
  EXPECT_EQ(field_of({{"measures.arm_length_uncertainty", "0.5"}}), "header.options[measures.arm_length_uncertainty]");
  EXPECT_EQ(field_of({{"measures.arm_length_uncertainty", "-0.01"}}),
            "header.options[measures.arm_length_uncertainty]");
}

}  // namespace
}  // namespace posefuse::session
