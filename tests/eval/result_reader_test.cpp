// session::read_result_files reads back what session::ResultFiles wrote, and names the file,
// line and column of whatever does not read as the writer would have written it.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <thread>

#include "../imu/expect_error.hpp"
#include "common/error.hpp"
#include "result_fixture.hpp"
#include "session/result_reader.hpp"

using namespace posefuse;

namespace {

// Replaces the first occurrence of `from` in a file.
void edit(const std::filesystem::path& file, const std::string& from, const std::string& to) {
  std::ifstream in(file);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
  std::ofstream(file) << text;
}

}  // namespace

TEST(ResultReader, ReadsBackWhatResultFilesWrote) {
  const auto dir = result_fixture::fresh_result_dir("read_back");
  result_fixture::FixtureSpec spec;
  spec.t0_us = 1000;
  result_fixture::write_fixture(dir, spec);
  const session::ResultDirectory r = session::read_result_files(dir);
  EXPECT_TRUE(r.has("imu_orientations/imu_right.csv"));
  EXPECT_TRUE(r.has("forearm_orientations/imu_right.csv"));
  EXPECT_TRUE(r.has("camera_joints.csv"));
  EXPECT_FALSE(r.has("smpl_joints.csv"));
  ASSERT_EQ(r.smpl_joint_rotations.size(), 24u * 10u);
  const session::JointRotationRow& rotation = r.smpl_joint_rotations[24 * 3 + 7];
  EXPECT_EQ(rotation.joint, 7);
  EXPECT_EQ(rotation.t_us, 1000 + static_cast<std::int64_t>(3 / 30.0 * 1e6));
  EXPECT_LT(geometry::angle_between(rotation.K_from_joint, result_fixture::fixture_K_from_joint(7, 3 / 30.0)), 1e-6);
  ASSERT_EQ(r.fit_energies.size(), 10u);
  EXPECT_EQ(r.fit_energies[3].t_us, rotation.t_us);
  EXPECT_DOUBLE_EQ(r.fit_energies[3].fit_energy, result_fixture::fixture_fit_energy(3 / 30.0));
  ASSERT_EQ(r.forearm_orientations.at("imu_right").size(), 27u);
  const auto& first = r.forearm_orientations.at("imu_right").front();
  EXPECT_EQ(first.t_us, 1000);
  EXPECT_NEAR(geometry::angle_between(first.q, result_fixture::fixture_K_from_F(0.0)), 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(first.pronation_rad, 0.1);
  EXPECT_EQ(first.uncertainty_rad, 0.05);
  EXPECT_EQ(first.confidence, 0.9);
  const auto& imu = r.imu_orientations.at("imu_right").front();
  EXPECT_EQ(imu.t_us, spec.device_t0_us);
  EXPECT_EQ(imu.uncertainty_rad, 0.04);
  EXPECT_EQ(imu.confidence, 0.95);
  ASSERT_EQ(r.camera_joints.size(), 250u);
  EXPECT_EQ(r.camera_joints[24].joint, 24);
  EXPECT_EQ(r.camera_joints[24].source, v1::GROUND_TRUTH);
  ASSERT_EQ(r.forearms.size(), 10u);
  EXPECT_EQ(r.forearms[3].arm, v1::RIGHT);
  ASSERT_EQ(r.imu_positions.size(), 10u);
  EXPECT_TRUE(r.imu_positions[9].p_K.isApprox(result_fixture::fixture_imu_K(9 / 30.0), 1e-12));
  EXPECT_EQ(r.imu_positions[9].source, v1::PREDICTED);
  ASSERT_FALSE(r.recovered.empty());
  EXPECT_EQ(r.recovered.front().method, v1::RecoveredSegment::SMOOTHER);
  ASSERT_TRUE(r.calibration.has_value());
  EXPECT_DOUBLE_EQ(r.calibration->forearms(0).r_m(), 0.035);
  ASSERT_EQ(r.joint_angles.size(), 10u);
  EXPECT_EQ(r.joint_angles[4].t_us, 1000 + static_cast<std::int64_t>(4 / 30.0 * 1e6));
  ASSERT_EQ(r.joint_angles[4].deg.size(), 15u);
  EXPECT_NEAR(*r.joint_angles[4].deg[7], result_fixture::fixture_angle_deg(7, 4 / 30.0), 1e-9);
  EXPECT_DOUBLE_EQ(r.joint_angles[4].confidence[3], 0.0);
  ASSERT_EQ(r.repetitions.size(), 3u);
  EXPECT_EQ(r.repetitions[1].angle, "right_elbow_flexion");
  EXPECT_DOUBLE_EQ(r.repetitions[1].range_deg, 50.0);
  EXPECT_DOUBLE_EQ(r.repetitions[1].t_start_s, 2.001);
  EXPECT_TRUE(r.repetitions[1].counted);
  EXPECT_DOUBLE_EQ(r.repetitions[1].confidence, 0.3);
  EXPECT_DOUBLE_EQ(r.repetitions[1].cut_ambiguity_deg, 0.0);
  EXPECT_FALSE(r.repetitions[2].counted);
}

// The last `n` comma-separated columns dropped from every line of a file.
void drop_last_columns(const std::filesystem::path& file, int n) {
  std::ifstream in(file);
  std::string out, line;
  while (std::getline(in, line)) {
    for (int k = 0; k < n; ++k) line.erase(line.rfind(','));
    out += line + "\n";
  }
  in.close();
  std::ofstream(file) << out;
}

// A column `name` appended to a CSV file, `value` in every row.
void append_column(const std::filesystem::path& file, const std::string& name, const std::string& value) {
  std::ifstream in(file);
  std::string text, line;
  for (int row = 0; std::getline(in, line); ++row) text += line + "," + (row == 0 ? name : value) + "\n";
  in.close();
  std::ofstream(file) << text;
}

TEST(ResultReader, RepetitionsWithoutTheConfidenceColumnStillRead) {
  // As written before each repetition carried its confidence (and its cut's ambiguity): the rows
  // read, with neither (NaN).
  const auto dir = result_fixture::fresh_result_dir("repetitions_without_confidence");
  result_fixture::write_fixture(dir, {});
  drop_last_columns(dir / "repetitions.csv", 2);
  const session::ResultDirectory r = session::read_result_files(dir);
  ASSERT_EQ(r.repetitions.size(), 3u);
  EXPECT_DOUBLE_EQ(r.repetitions[1].range_deg, 50.0);
  EXPECT_TRUE(r.repetitions[1].counted);
  EXPECT_TRUE(std::isnan(r.repetitions[1].confidence));
  EXPECT_TRUE(std::isnan(r.repetitions[1].cut_ambiguity_deg));
}

TEST(ResultReader, RepetitionsWithoutTheCutAmbiguityColumnStillRead) {
  // As written before each repetition carried its cut's ambiguity: the rows read, with none (NaN).
  const auto dir = result_fixture::fresh_result_dir("repetitions_without_cut_ambiguity");
  result_fixture::FixtureSpec spec;
  spec.uncertain_cut_ambiguity_deg = 40;
  result_fixture::write_fixture(dir, spec);
  EXPECT_DOUBLE_EQ(session::read_result_files(dir).repetitions[1].cut_ambiguity_deg, 40.0);
  drop_last_columns(dir / "repetitions.csv", 1);
  const session::ResultDirectory r = session::read_result_files(dir);
  ASSERT_EQ(r.repetitions.size(), 3u);
  EXPECT_DOUBLE_EQ(r.repetitions[1].confidence, 0.3);
  EXPECT_TRUE(std::isnan(r.repetitions[1].cut_ambiguity_deg));
}

TEST(ResultReader, ANegativeCutAmbiguityIsRefusedNamingTheCell) {
  const auto dir = result_fixture::fresh_result_dir("repetitions_bad_cut_ambiguity");
  result_fixture::write_fixture(dir, {});
  drop_last_columns(dir / "repetitions.csv", 1);
  append_column(dir / "repetitions.csv", "cut_ambiguity_deg", "-2");
  posefuse::testing::expect_error([&] { session::read_result_files(dir); }, ErrorCode::kInvalidArgument,
                                  "repetitions.csv:2:cut_ambiguity_deg");
}

TEST(ResultReader, ARepetitionConfidenceOutsideZeroToOneIsRefusedNamingTheCell) {
  const auto dir = result_fixture::fresh_result_dir("repetitions_bad_confidence");
  result_fixture::write_fixture(dir, {});
  drop_last_columns(dir / "repetitions.csv", 2);
  append_column(dir / "repetitions.csv", "confidence", "1.5");
  posefuse::testing::expect_error([&] { session::read_result_files(dir); }, ErrorCode::kInvalidArgument,
                                  "repetitions.csv:2:confidence");
}

TEST(ResultReader, OrientationFilesWithoutTheUncertaintyColumnsStillRead) {
  // As written before each sample carried its predicted error: the orientations read, with none.
  const auto dir = result_fixture::fresh_result_dir("without_uncertainty");
  result_fixture::write_fixture(dir, {});
  drop_last_columns(dir / "imu_orientations" / "imu_right.csv", 2);
  drop_last_columns(dir / "forearm_orientations" / "imu_right.csv", 2);
  const session::ResultDirectory r = session::read_result_files(dir);
  for (const auto* rows : {&r.imu_orientations.at("imu_right"), &r.forearm_orientations.at("imu_right")}) {
    ASSERT_EQ(rows->size(), 27u);
    EXPECT_FALSE(rows->front().uncertainty_rad.has_value());
    EXPECT_FALSE(rows->back().confidence.has_value());
  }
  EXPECT_DOUBLE_EQ(r.forearm_orientations.at("imu_right").back().pronation_rad, 0.1);
  // One column short of either layout is named.
  drop_last_columns(dir / "imu_orientations" / "imu_right.csv", 1);
  posefuse::testing::expect_error([&] { session::read_result_files(dir); }, ErrorCode::kInvalidArgument,
                                  "imu_orientations/imu_right.csv:1");
}

TEST(ResultReader, UndefinedAnglesAreEmptyCellsReadAsNone) {
  const auto dir = result_fixture::fresh_result_dir("undefined_angles");
  result_fixture::FixtureSpec spec;
  spec.right_pronation_defined = false;
  result_fixture::write_fixture(dir, spec);
  const session::ResultDirectory r = session::read_result_files(dir);
  ASSERT_EQ(r.joint_angles.size(), 10u);
  EXPECT_FALSE(r.joint_angles[0].deg[13].has_value());
  EXPECT_DOUBLE_EQ(r.joint_angles[0].confidence[13], 0.0);
  EXPECT_TRUE(r.joint_angles[0].deg[12].has_value());
}

TEST(ResultReader, NamesWhatIsWrong) {
  struct Case {
    const char* file;
    const char* from;
    const char* to;
    const char* field;
  };
  const Case cases[] = {
      {"imu_positions.csv", "t_us,device_id", "t,device_id", "imu_positions.csv:1"},
      {"imu_positions.csv", ",VISUAL", ",SEEN", "imu_positions.csv:2:source"},
      {"forearms.csv", "RIGHT", "MIDDLE", "forearms.csv:2:arm"},
      {"camera_joints.csv", "SpineMid", "Spine", "camera_joints.csv:3:joint_name"},
      {"forearm_orientations/imu_right.csv", "\n12500,", "\nnan,", "forearm_orientations/imu_right.csv:3:t_us"},
      // earlier than the row before
      {"forearm_orientations/imu_right.csv", "\n12500,", "\n-5,", "forearm_orientations/imu_right.csv:3:t_us"},
      // one field too many
      {"imu_orientations/imu_right.csv", "\n5012500,", "\n5012500,2,", "imu_orientations/imu_right.csv:3"},
      {"calibration.json", "\"forearms\"", "\"forearm_models\"", "calibration.json"},
      {"smpl_joint_rotations.csv", ",spine1,", ",spine,", "smpl_joint_rotations.csv:5:joint_name"},
      {"fit_energy.csv", "\n0,20\n", "\n0,inf\n", "fit_energy.csv:2:fit_energy"},
  };
  const auto dir = result_fixture::fresh_result_dir("bad");
  for (const Case& c : cases) {
    std::filesystem::remove_all(dir);
    result_fixture::write_fixture(dir, {});
    edit(dir / c.file, c.from, c.to);
    posefuse::testing::expect_error([&] { session::read_result_files(dir); }, ErrorCode::kInvalidArgument, c.field);
  }
  posefuse::testing::expect_error([&] { session::read_result_files(dir / "absent"); }, ErrorCode::kNotFound,
                                  (dir / "absent").string());
}

TEST(ResultFiles, RefusesAFrameWithSomeButNotAllJointRotations) {
  session::ResultFiles files(result_fixture::fresh_result_dir("rotations"));
  v1::FrameResult frame;
  frame.set_t_us(1);
  frame.add_smpl_joint_rotations()->set_w(1.0);
  posefuse::testing::expect_error([&] { files.write_frame(frame); }, ErrorCode::kInvalidArgument,
                                  "frame.smpl_joint_rotations", "has 1 rotations, not 0 or 24");
}

// Result directories written before the frame merge have two stages' rows in forearms.csv (the
// body fit's came seconds after the forearm stage's): they still read, the rows of one arm that
// go back in time sorted by arm and time; today's one row per frame and arm reads as above.
TEST(ResultReader, ForearmRowsOfTwoStagesAreSortedByArmAndTime) {
  const auto dir = result_fixture::fresh_result_dir("two_stages");
  result_fixture::write_fixture(dir, {});
  const session::ResultDirectory before = session::read_result_files(dir);
  ASSERT_GE(before.forearms.size(), 2u);
  const std::filesystem::path file = dir / "forearms.csv";
  std::ifstream in(file);
  std::string header, first_row, rest, line;
  std::getline(in, header);
  std::getline(in, first_row);
  while (std::getline(in, line)) rest += line + "\n";
  in.close();
  // The first frame's row again at the end, as the second stage would append it, but VISUAL.
  std::string late_row = first_row;
  late_row.replace(late_row.find("GROUND_TRUTH"), 12, "VISUAL");
  std::ofstream(file) << header << "\n" << first_row << "\n" << rest << late_row << "\n";
  const session::ResultDirectory r = session::read_result_files(dir);
  ASSERT_EQ(r.forearms.size(), before.forearms.size() + 1);
  for (std::size_t i = 1; i < r.forearms.size(); ++i) {
    const auto& a = r.forearms[i - 1];
    const auto& b = r.forearms[i];
    EXPECT_TRUE(a.arm < b.arm || (a.arm == b.arm && a.t_us <= b.t_us)) << "row " << i;
  }
  EXPECT_EQ(r.forearms[0].t_us, r.forearms[1].t_us);
  EXPECT_EQ(r.forearms[0].source, before.forearms[0].source);  // file order kept within a frame
  EXPECT_EQ(r.forearms[1].source, v1::VISUAL);
}

// Found by fuzz/fuzz_result_reader: a FIFO where a file belongs hung the reader, and a link to
// /dev/zero made it read without end. Links and anything but regular files are refused by name.
TEST(ResultReader, RefusesLinksFifosAndDevicesByName) {
  const auto dir = result_fixture::fresh_result_dir("links");
  const auto outside = result_fixture::fresh_result_dir("links_outside");
  result_fixture::write_fixture(outside, {});
  struct Case {
    const char* file;
    std::function<void(const std::filesystem::path&)> replace;
  };
  const Case cases[] = {
      {"camera_joints.csv",
       [&](const auto& path) { std::filesystem::create_symlink(outside / "camera_joints.csv", path); }},
      {"smpl_joint_rotations.csv", [](const auto& path) { std::filesystem::create_symlink("/dev/zero", path); }},
      {"calibration.json",
       [&](const auto& path) { std::filesystem::create_symlink(outside / "calibration.json", path); }},
      {"imu_orientations",
       [&](const auto& path) { std::filesystem::create_directory_symlink(outside / "imu_orientations", path); }},
      {"imu_orientations/imu_right.csv",
       [&](const auto& path) { std::filesystem::create_symlink(outside / "imu_orientations/imu_right.csv", path); }},
  };
  for (const Case& c : cases) {
    std::filesystem::remove_all(dir);
    result_fixture::write_fixture(dir, {});
    std::filesystem::remove_all(dir / c.file);
    c.replace(dir / c.file);
    posefuse::testing::expect_error([&] { session::read_result_files(dir); }, ErrorCode::kInvalidArgument, c.file);
  }

  // A FIFO with a writer that closes at once: read before, it was an empty file (or, without a
  // writer, a hang); now it is refused without being opened for reading.
  std::filesystem::remove_all(dir);
  result_fixture::write_fixture(dir, {});
  const auto fifo = dir / "forearms.csv";
  std::filesystem::remove(fifo);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::thread writer([&] {
    const int fd = ::open(fifo.c_str(), O_WRONLY);
    if (fd >= 0) ::close(fd);
  });
  posefuse::testing::expect_error([&] { session::read_result_files(dir); }, ErrorCode::kInvalidArgument,
                                  "forearms.csv");
  const int release = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);  // lets the writer's open return
  writer.join();
  ::close(release);
}
