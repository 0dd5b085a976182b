// A job store that refuses writes (a full disk) fails the affected job with a clear status and
// nothing else: the server goes on serving jobs, Fit calls and info. Through the real server on
// loopback, with the store's writes refused on demand (tests/server/faulty_job_store.hpp).
#include <chrono>
#include <thread>

#include <gtest/gtest.h>

#include "tests/server/faulty_job_store.hpp"
#include "tests/server/jobs_fixture.hpp"

namespace posefuse::server {
namespace {

class JobStoreFaultsTest : public JobsTest {
 protected:
  void start_with_faulty_store() {
    start({}, [this](const fs::path& data_dir) {
      auto store = std::make_unique<FaultyJobStore>(data_dir / "jobs.sqlite");
      faults_ = store.get();
      return store;
    });
    ASSERT_NE(faults_, nullptr);
  }

  // The demo session through Fit: its status, and whether the summary came.
  grpc::Status fit_demo(bool& summary) {
    grpc::ClientContext context;
    set_test_deadline(context);
    auto stream = stub_->Fit(&context);
    const auto chunks = demo::make_demo_session();
    std::thread sender([&] {
      for (const auto& chunk : chunks) {
        if (!stream->Write(chunk)) return;
      }
      stream->WritesDone();
    });
    summary = false;
    v1::FitResult result;
    while (stream->Read(&result)) summary = summary || result.has_summary();
    sender.join();
    return stream->Finish();
  }

  void expect_serving() {
    bool summary = false;
    const grpc::Status fit = fit_demo(summary);
    EXPECT_TRUE(fit.ok()) << fit.error_message();
    EXPECT_TRUE(summary);
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::ServerInfo info;
    EXPECT_TRUE(stub_->GetServerInfo(&context, {}, &info).ok());
  }

  FaultyJobStore* faults_ = nullptr;
};

TEST_F(JobStoreFaultsTest, JobWhoseResultsCannotBeStoredFailsAndTheServerServesOn) {
  start_with_faulty_store();
  faults_->refuse_results = true;
  v1::Job job;
  ASSERT_TRUE(submit("demo.pfchunks", job).ok());
  const auto states = watch(job.job_id());
  ASSERT_FALSE(states.empty());
  const v1::Job& failed = states.back();
  EXPECT_EQ(failed.state(), v1::Job::FAILED);
  EXPECT_EQ(failed.error_code(), static_cast<int>(grpc::StatusCode::RESOURCE_EXHAUSTED));
  EXPECT_NE(failed.error_message().find("job store refused a write"), std::string::npos) << failed.error_message();
  EXPECT_NE(failed.error_message().find("disk is full"), std::string::npos) << failed.error_message();
  // The failure was stored (only results were refused): GetJob says the same.
  {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::GetJobRequest request;
    request.set_job_id(job.job_id());
    v1::Job stored;
    ASSERT_TRUE(stub_->GetJob(&context, request, &stored).ok());
    EXPECT_EQ(stored.state(), v1::Job::FAILED);
  }
  expect_serving();

  // Space again: the next job runs to the end.
  faults_->refuse_results = false;
  v1::Job next;
  ASSERT_TRUE(submit("demo.pfchunks", next).ok());
  EXPECT_EQ(watch(next.job_id()).back().state(), v1::Job::SUCCEEDED);
}

TEST_F(JobStoreFaultsTest, EveryWriteRefusedGivesClearStatusesAndTheServerServesOn) {
  start_with_faulty_store();
  // No job can be created.
  faults_->refuse_creates = true;
  v1::Job job;
  grpc::Status status = submit("demo.pfchunks", job);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << status.error_message();
  EXPECT_EQ(status.error_message().rfind("job_store: ", 0), 0u) << status.error_message();
  faults_->refuse_creates = false;

  // A job is created, then not even its start can be stored.
  faults_->refuse_updates = true;
  ASSERT_TRUE(submit("demo.pfchunks", job).ok());
  ASSERT_TRUE(server_->jobs()->wait_idle(std::chrono::seconds(60)));
  // Cancelling it needs a write too: a status, not a crash.
  {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::CancelJobRequest request;
    request.set_job_id(job.job_id());
    v1::Job cancelled;
    status = stub_->CancelJob(&context, request, &cancelled);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << status.error_message();
  }
  expect_serving();
}

}  // namespace
}  // namespace posefuse::server
