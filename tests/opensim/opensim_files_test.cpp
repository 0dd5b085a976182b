// The OpenSim writers on results built in memory: the ground frame, each file's header and
// values, and what is written as NaN.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "../imu/expect_error.hpp"
#include "geometry/quaternion.hpp"
#include "measures/joint_angles.hpp"
#include "opensim/ground_frame.hpp"
#include "opensim/mot_file.hpp"
#include "opensim/sto_file.hpp"
#include "opensim/trc_file.hpp"
#include "session/frame_merge.hpp"

using namespace posefuse;

namespace {

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::vector<std::string> fields_of(const std::string& line, char separator = '\t') {
  std::vector<std::string> fields;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, separator)) fields.push_back(field);
  if (!line.empty() && line.back() == separator) fields.emplace_back();
  return fields;
}

Eigen::Vector3d joint_K(int frame, int joint) { return {0.02 * joint - 0.2, 1.0 - 0.05 * joint + 0.01 * frame, 2.5}; }

// Frames at 30 Hz (33'333 us apart), 24 SMPL joints each; joint 5 of frame 1 lost by the fit.
session::ResultDirectory smpl_results(int frames) {
  session::ResultDirectory results;
  for (int f = 0; f < frames; ++f) {
    for (int j = 0; j < 24; ++j) {
      session::JointRow row;
      row.t_us = 1'000'000 + f * 33'333;
      row.joint = j;
      row.p_K = joint_K(f, j);
      row.confidence = (f == 1 && j == 5) ? session::kLostFitConfidence : 0.9;
      results.smpl_joints.push_back(row);
    }
  }
  return results;
}

void set_K_from_W(session::ResultDirectory& results, const Eigen::Quaterniond& q) {
  results.calibration.emplace();
  v1::Quaternion& p = *results.calibration->mutable_k_from_w();
  p.set_w(q.w());
  p.set_x(q.x());
  p.set_y(q.y());
  p.set_z(q.z());
}

// W's z up mapped onto K's y, W's x onto K's x.
const Eigen::Quaterniond kLevelK_from_W(Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitX()));

}  // namespace

TEST(GroundFrame, LevelCameraGivesForwardUpRightWithTheOriginOnTheFloorBelowThePelvis) {
  session::ResultDirectory results = smpl_results(3);
  set_K_from_W(results, kLevelK_from_W);
  const opensim::GroundFrame ground = opensim::ground_frame(results);
  EXPECT_TRUE(ground.vertical_measured);
  // Facing the camera: forward is -z_K, up y_K, the subject's right the camera's left (+x_K).
  EXPECT_TRUE(ground.G_from_K.isApprox((Eigen::Matrix3d() << 0, 0, -1, 0, 1, 0, 1, 0, 0).finished(), 1e-12));
  const Eigen::Vector3d pelvis_G = ground.point_G(joint_K(0, 0));
  EXPECT_NEAR(pelvis_G.x(), 0.0, 1e-12);
  EXPECT_NEAR(pelvis_G.z(), 0.0, 1e-12);
  EXPECT_NEAR(ground.point_G(joint_K(0, 23)).y(), 0.0, 1e-12);  // the lowest joint of the session
  EXPECT_NEAR(pelvis_G.y(), 0.05 * 23, 1e-12);
}

TEST(GroundFrame, TiltedCameraPutsTheWorldsVerticalOnY) {
  session::ResultDirectory results = smpl_results(2);
  const Eigen::Quaterniond tilt(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()));
  set_K_from_W(results, tilt * kLevelK_from_W);
  const opensim::GroundFrame ground = opensim::ground_frame(results);
  const Eigen::Vector3d up_K = tilt * Eigen::Vector3d::UnitY();
  const Eigen::Vector3d a_K(0.1, 0.9, 2.0), b_K = a_K + 0.4 * up_K;
  const Eigen::Vector3d d_G = ground.point_G(b_K) - ground.point_G(a_K);
  EXPECT_TRUE(d_G.isApprox(Eigen::Vector3d(0, 0.4, 0), 1e-12)) << d_G.transpose();
}

TEST(GroundFrame, WithoutKFromWTheCameraIsAssumedLevel) {
  session::ResultDirectory results = smpl_results(2);
  results.calibration.emplace();  // K_from_W all zero: unknown
  const opensim::GroundFrame ground = opensim::ground_frame(results);
  EXPECT_FALSE(ground.vertical_measured);
  EXPECT_TRUE(ground.G_from_K.isApprox((Eigen::Matrix3d() << 0, 0, -1, 0, 1, 0, 1, 0, 0).finished(), 1e-12));
}

TEST(TrcFile, WritesOpenSimsHeaderAndEveryJointInTheGround) {
  const session::ResultDirectory results = smpl_results(3);
  const opensim::GroundFrame ground = opensim::ground_frame(results);
  std::ostringstream out;
  const opensim::TrcSummary summary = opensim::write_trc(results, ground, "markers.trc", out);
  EXPECT_EQ(summary.frames, 3u);
  EXPECT_EQ(summary.markers, 24u);
  EXPECT_EQ(summary.missing, 1u);
  EXPECT_NEAR(summary.rate_hz, 30.0, 1e-3);
  const std::vector<std::string> lines = lines_of(out.str());
  ASSERT_EQ(lines.size(), 9u);  // 5 header lines, a blank line, 3 frames
  EXPECT_EQ(lines[0], "PathFileType\t4\t(X/Y/Z)\tmarkers.trc");
  const std::vector<std::string> counts = fields_of(lines[2]);
  ASSERT_EQ(counts.size(), 8u);
  EXPECT_NEAR(std::stod(counts[0]), 30.0, 1e-3);
  EXPECT_EQ(counts[1], counts[0]);
  EXPECT_EQ(counts[2], "3");
  EXPECT_EQ(counts[3], "24");
  EXPECT_EQ(counts[4], "m");
  EXPECT_EQ(counts[5], counts[0]);
  EXPECT_EQ(counts[7], "3");
  const std::vector<std::string> names = fields_of(lines[3]);
  ASSERT_EQ(names.size(), 2u + 3u * 24u);
  EXPECT_EQ(names[0], "Frame#");
  EXPECT_EQ(names[2], "pelvis");
  EXPECT_EQ(names[2 + 3 * 21], "right_wrist");
  const std::vector<std::string> axes = fields_of(lines[4]);
  EXPECT_EQ(axes[2], "X1");
  EXPECT_EQ(axes.back(), "Z24");
  EXPECT_TRUE(lines[5].empty());
  for (int f = 0; f < 3; ++f) {
    const std::vector<std::string> row = fields_of(lines[6 + static_cast<std::size_t>(f)]);
    ASSERT_EQ(row.size(), 2u + 3u * 24u);
    EXPECT_EQ(row[0], std::to_string(f + 1));
    EXPECT_DOUBLE_EQ(std::stod(row[1]), 1.0 + f * 0.033333);
    for (int j = 0; j < 24; ++j) {
      const auto at = static_cast<std::size_t>(2 + 3 * j);
      if (f == 1 && j == 5) {
        EXPECT_EQ(row[at], "NaN");
        EXPECT_EQ(row[at + 2], "NaN");
        continue;
      }
      const Eigen::Vector3d p_G = ground.point_G(joint_K(f, j));
      EXPECT_NEAR(std::stod(row[at]), p_G.x(), 1e-12);
      EXPECT_NEAR(std::stod(row[at + 1]), p_G.y(), 1e-12);
      EXPECT_NEAR(std::stod(row[at + 2]), p_G.z(), 1e-12);
    }
  }
}

TEST(TrcFile, FallsBackToTheCameraSkeletonAndRefusesASingleFrame) {
  session::ResultDirectory results;
  for (int f = 0; f < 2; ++f) {
    for (int j = 0; j < 25; ++j) results.camera_joints.push_back({f * 33'333, j, joint_K(f, j), v1::VISUAL, 1.0});
  }
  std::ostringstream out;
  EXPECT_EQ(opensim::write_trc(results, opensim::ground_frame(results), "k.trc", out).markers, 25u);
  EXPECT_EQ(fields_of(lines_of(out.str())[3])[2], "SpineBase");
  const session::ResultDirectory one = smpl_results(1);
  posefuse::testing::expect_error([&] { opensim::write_trc(one, opensim::ground_frame(one), "x.trc", out); },
                                  ErrorCode::kFailedPrecondition, "smpl_joints.csv", "at least two frames");
  const session::ResultDirectory none;
  posefuse::testing::expect_error([&] { opensim::write_trc(none, opensim::ground_frame(none), "x.trc", out); },
                                  ErrorCode::kFailedPrecondition, "camera_joints.csv", "have 0");
}

TEST(MotFile, WritesTheAnglesInDegreesWithNaNWhereTheyAreUnusable) {
  session::ResultDirectory results;
  for (int f = 0; f < 2; ++f) {
    session::AngleRow row;
    row.t_us = 2'000'000 + f * 33'333;
    for (int a = 0; a < measures::kAngleCount; ++a) {
      row.deg.emplace_back(10.0 * a + f);
      row.confidence.push_back(0.8);
    }
    row.deg[2].reset();       // undefined
    row.confidence[3] = 0.0;  // held
    results.joint_angles.push_back(row);
  }
  std::ostringstream out;
  const opensim::MotSummary summary = opensim::write_mot(results, "session", out);
  EXPECT_EQ(summary.rows, 2u);
  EXPECT_EQ(summary.missing, 4u);
  const std::vector<std::string> lines = lines_of(out.str());
  ASSERT_EQ(lines.size(), 9u);
  EXPECT_EQ(lines[0], "session");
  EXPECT_EQ(lines[1], "version=1");
  EXPECT_EQ(lines[2], "nRows=2");
  EXPECT_EQ(lines[3], "nColumns=16");
  EXPECT_EQ(lines[4], "inDegrees=yes");
  EXPECT_EQ(lines[5], "endheader");
  const std::vector<std::string> header = fields_of(lines[6]);
  ASSERT_EQ(header.size(), 16u);
  EXPECT_EQ(header[0], "time");
  EXPECT_EQ(header[1], "thorax_flexion");
  EXPECT_EQ(header[15], std::string(measures::angle_name(static_cast<measures::Angle>(14))));
  const std::vector<std::string> second = fields_of(lines[8]);
  EXPECT_EQ(second[0], "2.033333");
  EXPECT_EQ(second[3], "NaN");
  EXPECT_EQ(second[4], "NaN");
  EXPECT_DOUBLE_EQ(std::stod(second[2]), 11.0);
  EXPECT_DOUBLE_EQ(std::stod(second[15]), 141.0);
  posefuse::testing::expect_error([&] { opensim::write_mot(session::ResultDirectory{}, "x", out); },
                                  ErrorCode::kFailedPrecondition, "joint_angles.csv", "fit.enabled");
}

TEST(StoFile, WritesEachImuInTheGroundOnTheCameraClockAtCommonTimes) {
  session::ResultDirectory results = smpl_results(2);
  set_K_from_W(results, kLevelK_from_W);
  v1::ForearmModel& model = *results.calibration->add_forearms();
  model.set_arm(v1::RIGHT);
  model.set_device_id("imu_r");
  (*results.calibration->mutable_clock_offset_us())["imu_r"] = 1'000;
  (*results.calibration->mutable_clock_offset_us())["wrist2"] = -2'000;
  const auto W_from_A = [](double t_s) { return geometry::quat_from_rotation_vector({0.5 * t_s, 0.2, -0.1}); };
  for (int i = 0; i < 100; ++i) {  // 100 Hz; the second IMU at 50 Hz, starting later
    results.imu_orientations["imu_r"].push_back({i * 10'000, W_from_A(i * 0.01), 0.0, {}, {}});
    if (i % 2 == 0 && i >= 20)
      results.imu_orientations["wrist2"].push_back({i * 10'000 + 5'000, W_from_A(i * 0.01), 0.0, {}, {}});
  }
  const opensim::GroundFrame ground = opensim::ground_frame(results);
  std::ostringstream out;
  const opensim::StoSummary summary = opensim::write_sto(results, ground, out);
  EXPECT_TRUE(summary.camera_ground);
  EXPECT_TRUE(summary.camera_clock);
  EXPECT_EQ(summary.imus, 2u);
  const std::vector<std::string> lines = lines_of(out.str());
  EXPECT_EQ(lines[1], "DataType=Quaternion");
  const auto end = std::find(lines.begin(), lines.end(), "endheader");
  ASSERT_NE(end, lines.end());
  const std::vector<std::string> header = fields_of(*(end + 1));
  ASSERT_EQ(header.size(), 3u);
  EXPECT_EQ(header[0], "time");
  EXPECT_EQ(header[1], "radius_r_imu");
  EXPECT_EQ(header[2], "wrist2");
  // imu_r (camera 1 ms + 10 ms i) has the most samples; wrist2 covers camera 0.203-0.983 s.
  const std::vector<std::string> first = fields_of(*(end + 2));
  EXPECT_EQ(first[0], "0.211000");
  EXPECT_EQ(summary.rows, 78u);  // 0.211 ... 0.981
  const Eigen::Matrix3d G_from_W = ground.G_from_K * kLevelK_from_W.toRotationMatrix();
  for (std::size_t r = 0; r < summary.rows; r += 7) {
    const std::vector<std::string> row = fields_of(*(end + 2 + static_cast<std::ptrdiff_t>(r)));
    const double t_s = std::stod(row[0]);
    for (std::size_t c = 1; c <= 2; ++c) {
      const std::vector<std::string> wxyz = fields_of(row[c], ',');
      ASSERT_EQ(wxyz.size(), 4u);
      const Eigen::Quaterniond got(std::stod(wxyz[0]), std::stod(wxyz[1]), std::stod(wxyz[2]), std::stod(wxyz[3]));
      // Device time: camera time minus the offset; wrist2's samples are slerped.
      const double device_s = t_s - (c == 1 ? 0.001 : -0.002);
      const Eigen::Quaterniond want(G_from_W * W_from_A(c == 1 ? device_s : device_s - 0.005).toRotationMatrix());
      EXPECT_LT(geometry::angle_between(got, want), c == 1 ? 1e-6 : 2e-4) << "row " << r << " column " << c;
    }
  }
}

TEST(StoFile, WithoutCalibrationStaysInTheWorldOnTheDeviceClock) {
  session::ResultDirectory results;
  results.imu_orientations["a"] = {{0, geometry::Quat::Identity(), 0.0, {}, {}},
                                   {10'000, geometry::Quat::Identity(), 0.0, {}, {}}};
  std::ostringstream out;
  const opensim::StoSummary summary = opensim::write_sto(results, opensim::ground_frame(results), out);
  EXPECT_FALSE(summary.camera_ground);
  EXPECT_FALSE(summary.camera_clock);
  EXPECT_NE(out.str().find("ground=north\nclock=device\n"), std::string::npos);
  // Identity W_from_A in the north ground: W's z (up) is G's y.
  const std::vector<std::string> lines = lines_of(out.str());
  const std::vector<std::string> wxyz = fields_of(fields_of(lines.back())[1], ',');
  const Eigen::Quaterniond got(std::stod(wxyz[0]), std::stod(wxyz[1]), std::stod(wxyz[2]), std::stod(wxyz[3]));
  EXPECT_TRUE((got * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  posefuse::testing::expect_error([&] { opensim::write_sto(session::ResultDirectory{}, opensim::GroundFrame{}, out); },
                                  ErrorCode::kFailedPrecondition, "imu_orientations", "no IMU orientations");
}
