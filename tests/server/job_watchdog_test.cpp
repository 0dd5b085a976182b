// A long or stuck job can neither starve Fit nor run for ever (server/job_runner.hpp): jobs run
// on threads of their own, an attempt past --job-deadline-s or --job-stall-s fails with
// DEADLINE_EXCEEDED, and a cancel reaches a job whose thread is blocked inside a read. Through
// the real server on loopback; the job is held inside the read of its uploaded recording by
// the store (tests/server/faulty_job_store.hpp).
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <future>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

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

  // Options with the watchdog off; each test turns on what it tries.
  static ServerOptions options() {
    ServerOptions options;
    options.job_deadline_s = 0;
    options.job_stall_s = 0;
    return options;
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

  grpc::Status cancel(const std::string& id) {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::CancelJobRequest request;
    request.set_job_id(id);
    v1::Job job;
    return stub_->CancelJob(&context, request, &job);
  }

  v1::Job final_state(const std::string& id) {
    const auto states = watch(id);
    return states.empty() ? v1::Job() : states.back();
  }

  // Lets the held job's thread return and waits for it: whatever it tries to write then is
  // refused (the job's end was written without it), so the stored job stays as it was.
  v1::Job stored_after_release(const std::string& id) {
    gate_.open();
    EXPECT_TRUE(server_->jobs()->wait_idle(std::chrono::seconds(60)));
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::GetJobRequest request;
    request.set_job_id(id);
    v1::Job job;
    const grpc::Status status = stub_->GetJob(&context, request, &job);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return job;
  }

  // Heartbeats (and so the watchdog's rounds) every 50 ms.
  static ServerOptions quick_heartbeat(ServerOptions options) {
    options.job_lease_s = 5;
    options.job_heartbeat_s = 0.05;
    return options;
  }

  Gate gate_;
};

TEST_F(JobWatchdogTest, JobStuckInsideAReadLeavesFitServedWithOneWorker) {
  ServerOptions options = this->options();
  options.workers = 1;
  options.max_jobs = 1;
  start_with_upload(options, [this] { gate_.pass(); });
  ASSERT_TRUE(gate_.wait_entered());
  bool summary = false;
  const grpc::Status fit = fit_demo(summary);
  EXPECT_TRUE(fit.ok()) << fit.error_message();
  EXPECT_TRUE(summary);
}

TEST_F(JobWatchdogTest, JobPastItsDeadlineFailsWithDeadlineExceeded) {
  // The read takes longer than the whole deadline; the job stops at its first chunk.
  ServerOptions options = this->options();
  options.job_deadline_s = 0.1;
  const std::string id =
      start_with_upload(options, [] { std::this_thread::sleep_for(std::chrono::milliseconds(300)); });
  const v1::Job job = final_state(id);
  EXPECT_EQ(job.state(), v1::Job::FAILED);
  EXPECT_EQ(job.error_code(), static_cast<int>(grpc::StatusCode::DEADLINE_EXCEEDED));
  EXPECT_EQ(job.error_message().rfind("job: ran for longer than --job-deadline-s (0.1", 0), 0u) << job.error_message();
}

TEST_F(JobWatchdogTest, JobBlockedInsideAReadFailsWhenItReadsNoChunkForTheStallLimit) {
  ServerOptions options = quick_heartbeat(this->options());
  options.job_stall_s = 0.2;
  const std::string id = start_with_upload(options, [this] { gate_.pass(); });
  const v1::Job job = final_state(id);
  EXPECT_EQ(job.state(), v1::Job::FAILED);
  EXPECT_EQ(job.error_code(), static_cast<int>(grpc::StatusCode::DEADLINE_EXCEEDED));
  EXPECT_EQ(job.error_message().rfind("job: read no chunk of its recording for --job-stall-s (0.2", 0), 0u)
      << job.error_message();

  const v1::Job stored = stored_after_release(id);
  EXPECT_EQ(stored.state(), v1::Job::FAILED);
  EXPECT_EQ(stored.error_message(), job.error_message());
}

TEST_F(JobWatchdogTest, CancelReachesAJobBlockedInsideARead) {
  const std::string id = start_with_upload(quick_heartbeat(options()), [this] { gate_.pass(); });
  ASSERT_TRUE(gate_.wait_entered());
  const grpc::Status cancelled = cancel(id);
  ASSERT_TRUE(cancelled.ok()) << cancelled.error_message();
  EXPECT_EQ(final_state(id).state(), v1::Job::CANCELLED);
  EXPECT_EQ(stored_after_release(id).state(), v1::Job::CANCELLED);
}

TEST_F(JobWatchdogTest, AJobBlockedInsideAReadGivesUpItsSlotOnceTheWatchdogEndsIt) {
  // Ended by a cancel, which the watchdog stores for the blocked thread; no stall limit, which
  // a healthy job under the sanitizers could reach between two chunks.
  ServerOptions one_slot = quick_heartbeat(options());
  one_slot.max_jobs = 1;
  auto first = std::make_shared<std::atomic<bool>>(true);
  const std::string blocked = start_with_upload(one_slot, [this, first] {
    if (first->exchange(false)) gate_.pass();
  });
  ASSERT_TRUE(gate_.wait_entered());
  const grpc::Status cancelled = cancel(blocked);
  ASSERT_TRUE(cancelled.ok()) << cancelled.error_message();
  EXPECT_EQ(final_state(blocked).state(), v1::Job::CANCELLED);
  // The only slot's thread is still inside the read; the next job runs all the same.
  v1::Job next;
  const grpc::Status status = upload(demo::make_demo_session(), next);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(final_state(next.job_id()).state(), v1::Job::SUCCEEDED);
}

TEST_F(JobWatchdogTest, ShutdownReturnsNamingAJobBlockedInsideARead) {
  ServerOptions bounded = options();
  bounded.shutdown_grace_s = 0.2;
  const std::string id = start_with_upload(bounded, [this] { gate_.pass(); });
  ASSERT_TRUE(gate_.wait_entered());
  // Without a bound, shutdown waits for the blocked thread (until TearDown opens the gate).
  auto stopped = std::async(std::launch::async, [this] { return server_->shutdown(); });
  ASSERT_EQ(stopped.wait_for(std::chrono::seconds(60)), std::future_status::ready);
  EXPECT_EQ(stopped.get(), std::vector<std::string>{id});
  // The job is still the store's RUNNING one, for its lease to expire and another worker to take.
  EXPECT_EQ(server_->jobs()->store().get(id)->job.state(), v1::Job::RUNNING);
}

}  // namespace
}  // namespace posefuse::server
