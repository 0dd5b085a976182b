// DirectoryReader never leaves its recording and never blocks: links (to files outside or
// inside), ids that would make a path outside the imu/ folder, and FIFOs are refused by name,
// and no error quotes what a file holds.
#include <sys/stat.h>

#include <gtest/gtest.h>

#include <fstream>

#include "fixture.hpp"
#include "session/directory_reader.hpp"
#include "session/directory_writer.hpp"

namespace posefuse::session::testing {
namespace {

namespace fs = std::filesystem;

constexpr const char* kSecret = "SECRET-FIRST-LINE-OF-AN-OUTSIDE-FILE";

std::vector<SessionChunk> read_directory(const fs::path& directory) {
  DirectoryReader reader(directory);
  return read_all(reader);
}

void write_directory(const fs::path& directory, const std::vector<SessionChunk>& chunks) {
  DirectoryWriter writer(directory);
  for (const SessionChunk& c : chunks) writer.write(c);
  writer.finish();
}

void replace_first(const fs::path& path, const std::string& from, const std::string& to) {
  std::ifstream in(path, std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  const std::size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
}

fs::path first_file_in(const fs::path& folder) {
  for (const auto& entry : fs::directory_iterator(folder)) return entry.path();
  ADD_FAILURE() << "empty folder " << folder;
  return {};
}

// Reading the directory fails with kInvalidArgument naming `field`, and the message does not
// quote the outside file.
void expect_refused(const fs::path& recording, const std::string& field) {
  try {
    read_directory(recording);
    ADD_FAILURE() << "the recording was read";
  } catch (const Error& error) {
    EXPECT_EQ(error.code(), ErrorCode::kInvalidArgument) << error.what();
    EXPECT_EQ(error.field(), field) << error.what();
    EXPECT_EQ(std::string(error.what()).find(kSecret), std::string::npos) << error.what();
  }
}

class RecordingConfinement : public ::testing::Test {
 protected:
  void SetUp() override {
    write_directory(recording_, make_session());
    fs::create_directories(outside_);
    std::ofstream(outside_ / "secret.csv") << kSecret << "\n";
  }
  TempDir dir_;
  const fs::path recording_ = dir_ / "recordings/rec";
  const fs::path outside_ = dir_ / "outside";
};

TEST_F(RecordingConfinement, DepthPngThatLinksOutsideTheRecordingIsRefused) {
  // The link's target is a valid PNG of the right size: following it would read it happily.
  const fs::path frame = first_file_in(recording_ / "depth");
  fs::copy_file(frame, outside_ / "frame.png");
  fs::remove(frame);
  fs::create_symlink(outside_ / "frame.png", frame);
  expect_refused(recording_, "depth/" + frame.filename().string());
}

TEST_F(RecordingConfinement, LinkToAFileInsideTheRecordingIsRefusedToo) {
  fs::rename(recording_ / "skeleton.csv", recording_ / "skeleton_copy.csv");
  fs::create_symlink("skeleton_copy.csv", recording_ / "skeleton.csv");
  expect_refused(recording_, "skeleton.csv");
}

TEST_F(RecordingConfinement, LinkedFolderIsRefused) {
  fs::rename(recording_ / "imu", outside_ / "imu");
  fs::create_symlink(outside_ / "imu", recording_ / "imu");
  expect_refused(recording_, "imu");
}

TEST_F(RecordingConfinement, DeviceIdThatLeavesTheImuFolderIsRefusedBeforeAnyPathIsMade) {
  // recordings/rec/imu/../../../outside/secret.csv is outside/secret.csv.
  replace_first(recording_ / "header.json", "\"wrist_r\"", "\"../../../outside/secret\"");
  try {
    read_directory(recording_);
    ADD_FAILURE() << "the recording was read";
  } catch (const Error& error) {
    EXPECT_EQ(error.code(), ErrorCode::kInvalidArgument) << error.what();
    EXPECT_EQ(error.field().rfind("header.json.imu_devices[", 0), 0u) << error.what();
    EXPECT_NE(error.field().find("].device_id"), std::string::npos) << error.what();
    EXPECT_EQ(std::string(error.what()).find(kSecret), std::string::npos) << error.what();
    EXPECT_EQ(std::string(error.what()).find("outside"), std::string::npos) << error.what();
  }
}

TEST_F(RecordingConfinement, CsvWithAnotherHeaderRowIsNotQuoted) {
  std::ofstream(recording_ / "imu/wrist_r.csv", std::ios::trunc) << kSecret << "\n1,2,3\n";
  try {
    read_directory(recording_);
    ADD_FAILURE() << "the recording was read";
  } catch (const Error& error) {
    EXPECT_EQ(error.field(), "imu/wrist_r.csv:1") << error.what();
    EXPECT_EQ(std::string(error.what()).find(kSecret), std::string::npos) << error.what();
  }
}

TEST_F(RecordingConfinement, FifoInsteadOfAFileIsRefusedWithoutBlocking) {
  // Opening a FIFO for reading blocks until a writer comes: none ever does here.
  fs::remove(recording_ / "sync_events.csv");
  ASSERT_EQ(::mkfifo((recording_ / "sync_events.csv").c_str(), 0600), 0);
  expect_refused(recording_, "sync_events.csv");

  const fs::path frame = first_file_in(recording_ / "body_index");
  fs::remove(recording_ / "sync_events.csv");
  fs::remove(frame);
  ASSERT_EQ(::mkfifo(frame.c_str(), 0600), 0);
  expect_refused(recording_, "body_index/" + frame.filename().string());
}

}  // namespace
}  // namespace posefuse::session::testing
