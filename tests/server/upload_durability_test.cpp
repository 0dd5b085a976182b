// An uploaded recording is on the disk, bytes and name, before the job row that names it is
// written (docs/server.md "Jobs by upload"), so a crash right after SubmitJob answered cannot
// leave a job whose file is lost. Through the real server on loopback; the fsync calls are
// observed by defining fsync in this test binary (the server's calls bind to it), which records
// the file each call syncs and then makes the real system call.
#include <sys/syscall.h>
#include <unistd.h>

#include <mutex>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/server/faulty_job_store.hpp"
#include "tests/server/jobs_fixture.hpp"

namespace {

std::mutex synced_mu;
std::vector<std::string> synced;  // what each fsync call synced, in order

std::string path_of(int fd) {
  char target[4096];
  const ssize_t n = ::readlink(("/proc/self/fd/" + std::to_string(fd)).c_str(), target, sizeof target);
  return n > 0 ? std::string(target, static_cast<std::size_t>(n)) : std::string();
}

}  // namespace

extern "C" int fsync(int fd) {
  {
    const std::lock_guard lock(synced_mu);
    synced.push_back(path_of(fd));
  }
  return static_cast<int>(::syscall(SYS_fsync, fd));
}

namespace posefuse::server {
namespace {

TEST_F(JobsTest, UploadIsOnTheDiskBeforeItsJobRowIsWritten) {
  std::vector<std::string> synced_before_row;
  start({}, [&](const fs::path& data_dir) {
    auto store = std::make_unique<FaultyJobStore>(data_dir / "jobs.sqlite");
    store->before_create = [&] {
      const std::lock_guard lock(synced_mu);
      synced_before_row = synced;
    };
    return store;
  });
  v1::Job job;
  const grpc::Status status = upload(demo::make_demo_session(), job);
  ASSERT_TRUE(status.ok()) << status.error_message();

  // The spooled file (still under its partial name), then the folder that holds its final name.
  const std::string spool = fs::canonical(dir_ / "data" / "uploads").string();
  std::vector<std::string> spool_syncs;
  for (const std::string& path : synced_before_row) {
    if (path.rfind(spool, 0) == 0) spool_syncs.push_back(path);
  }
  ASSERT_EQ(spool_syncs.size(), 2u) << ::testing::PrintToString(synced_before_row);
  EXPECT_EQ(fs::path(spool_syncs[0]).parent_path(), spool);
  EXPECT_EQ(fs::path(spool_syncs[0]).extension(), ".partial");
  EXPECT_EQ(spool_syncs[1], spool);
  EXPECT_EQ(watch(job.job_id()).back().state(), v1::Job::SUCCEEDED);
}

}  // namespace
}  // namespace posefuse::server
