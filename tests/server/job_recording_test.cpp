// What a job reads stays beneath the recordings root and cannot block the job queue
// (server/job_recording.hpp): through the real server on loopback.
#include <sys/stat.h>

#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "session/convert.hpp"
#include "tests/server/jobs_fixture.hpp"

namespace posefuse::server {
namespace {

constexpr const char* kSecret = "SECRET-FIRST-LINE-OF-A-FILE-OUTSIDE-THE-ROOT";

class JobRecordingTest : public JobsTest {
 protected:
  void SetUp() override {
    JobsTest::SetUp();
    fs::create_directories(dir_ / "outside");
    std::ofstream(dir_ / "outside" / "secret.csv") << kSecret << "\n";
    session::chunk_file_to_directory(dir_ / "recordings" / "demo.pfchunks", recording_);
  }

  // Submits `uri`, waits for the end, returns the final state.
  v1::Job run_job(const std::string& uri) {
    v1::Job job;
    const grpc::Status status = submit(uri, job);
    EXPECT_TRUE(status.ok()) << status.error_message();
    const auto states = watch(job.job_id());
    return states.empty() ? v1::Job() : states.back();
  }

  void expect_failed_without_the_secret(const v1::Job& job, const std::string& field) {
    EXPECT_EQ(job.state(), v1::Job::FAILED);
    EXPECT_EQ(job.error_code(), static_cast<int>(grpc::StatusCode::INVALID_ARGUMENT));
    EXPECT_EQ(job.error_message().rfind(field, 0), 0u) << job.error_message();
    EXPECT_EQ(job.error_message().find(kSecret), std::string::npos) << job.error_message();
  }

  const fs::path recording_ = dir_ / "recordings" / "rec";
};

TEST_F(JobRecordingTest, RecordingDirectoryIsReadAsAJob) {
  // The directory form of the demo session, so that the refusals below are about what they
  // change and nothing else.
  start();
  const v1::Job job = run_job("rec");
  EXPECT_EQ(job.state(), v1::Job::SUCCEEDED) << job.error_message();
  EXPECT_EQ(job.summary().depth_frames(), 300u);
}

TEST_F(JobRecordingTest, DeviceIdThatPointsOutsideTheRootFailsTheJobWithoutReadingTheFile) {
  // rec/imu/../../../outside/secret.csv is <dir>/outside/secret.csv.
  const fs::path header = recording_ / "header.json";
  std::ifstream in(header);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  const std::string id = std::string("\"") + demo::kArmDevice + "\"";
  const std::size_t at = text.find(id);
  ASSERT_NE(at, std::string::npos);
  text.replace(at, id.size(), "\"../../../outside/secret\"");
  std::ofstream(header, std::ios::trunc) << text;
  start();
  expect_failed_without_the_secret(run_job("rec"), "header.json.imu_devices[");
}

TEST_F(JobRecordingTest, DepthPngThatLinksOutsideTheRootFailsTheJob) {
  fs::path frame;
  for (const auto& entry : fs::directory_iterator(recording_ / "depth")) frame = entry.path();
  ASSERT_FALSE(frame.empty());
  fs::copy_file(frame, dir_ / "outside" / "frame.png");
  fs::remove(frame);
  fs::create_symlink(dir_ / "outside" / "frame.png", frame);
  start();
  expect_failed_without_the_secret(run_job("rec"), "depth/" + frame.filename().string() + ": ");
}

TEST_F(JobRecordingTest, FifoAsARecordingFailsTheJobAndTheNextJobRuns) {
  // Opening a FIFO for reading waits for a writer; none comes. With one job at a time
  // (--max-jobs 1, the default) a job stuck there would stop the queue for good.
  ASSERT_EQ(::mkfifo((dir_ / "recordings" / "fifo.pfchunks").c_str(), 0600), 0);
  ServerOptions options;
  options.max_jobs = 1;
  start(options);
  const v1::Job fifo = run_job("fifo.pfchunks");
  EXPECT_EQ(fifo.state(), v1::Job::FAILED);
  EXPECT_EQ(fifo.error_code(), static_cast<int>(grpc::StatusCode::INVALID_ARGUMENT));
  EXPECT_EQ(fifo.error_message().rfind("spec.recording_uri: ", 0), 0u) << fifo.error_message();
  EXPECT_NE(fifo.error_message().find("regular file"), std::string::npos) << fifo.error_message();

  const v1::Job next = run_job("demo.pfchunks");
  EXPECT_EQ(next.state(), v1::Job::SUCCEEDED) << next.error_message();
}

}  // namespace
}  // namespace posefuse::server
