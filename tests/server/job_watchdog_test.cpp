// A long or stuck job cannot starve Fit (server/job_runner.hpp): jobs run on threads of their
// own. Through the real server on loopback; the job is held inside the read of its uploaded
// recording by the store (tests/server/faulty_job_store.hpp).
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

#include <gtest/gtest.h>

#include "tests/server/faulty_job_store.hpp"
#include "tests/server/jobs_fixture.hpp"

namespace posefuse::server {
namespace {

// Holds whoever passes it until it is opened.
class Gate {
 public:
  void pass() {
    std::unique_lock lock(mu_);
    entered_ = true;
    changed_.notify_all();
    changed_.wait(lock, [this] { return open_; });
  }
  // False when nobody came within a generous time.
  bool wait_entered() {
    std::unique_lock lock(mu_);
    return changed_.wait_for(lock, std::chrono::seconds(60), [this] { return entered_; });
  }
  void open() {
    std::lock_guard lock(mu_);
    open_ = true;
    changed_.notify_all();
  }

 private:
  std::mutex mu_;
  std::condition_variable changed_;
  bool entered_ = false;
  bool open_ = false;
};

class JobWatchdogTest : public JobsTest {
 protected:
  void TearDown() override {
    gate_.open();  // the held job's thread returns, so that the server can stop
    server_.reset();
  }

  // Starts the server with `options` and the store calling `before_fetch` as a job's worker
  // fetches its upload; submits the demo session by upload.
  std::string start_with_upload(ServerOptions options, std::function<void()> before_fetch) {
    start(options, [before_fetch](const fs::path& data_dir) {
      auto store = std::make_unique<FaultyJobStore>(data_dir / "jobs.sqlite");
      store->before_fetch = before_fetch;
      return store;
    });
    v1::Job job;
    const grpc::Status status = upload(demo::make_demo_session(), job);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return job.job_id();
  }

  Gate gate_;
};

TEST_F(JobWatchdogTest, JobStuckInsideAReadLeavesFitServedWithOneWorker) {
  ServerOptions options;
  options.workers = 1;
  options.max_jobs = 1;
  start_with_upload(options, [this] { gate_.pass(); });
  ASSERT_TRUE(gate_.wait_entered());
  bool summary = false;
  const grpc::Status fit = fit_demo(summary);
  EXPECT_TRUE(fit.ok()) << fit.error_message();
  EXPECT_TRUE(summary);
}

}  // namespace
}  // namespace posefuse::server
