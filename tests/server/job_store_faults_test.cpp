// A job store that refuses writes (a full disk) fails the affected job with a clear status and
// nothing else: the server goes on serving jobs, Fit calls and info, and the jobs' own health
// service says NOT_SERVING until the store takes writes again. A store that cannot even be
// opened at start leaves the server up too. Through the real server on loopback, with the
// store's writes refused on demand (tests/server/faulty_job_store.hpp) or a real SQLite file
// that cannot be opened.
#include <chrono>
#include <fstream>
#include <thread>

#include <gtest/gtest.h>

#include "tests/server/faulty_job_store.hpp"
#include "tests/server/health_check.hpp"
#include "tests/server/jobs_fixture.hpp"

namespace posefuse::server {
namespace {

using HealthResponse = grpc::health::v1::HealthCheckResponse;
using HealthStatus = HealthResponse::ServingStatus;

class JobStoreFaultsTest : public JobsTest {
 protected:
  // Heartbeats a few times a second, so that the jobs' health follows the store at once.
  static ServerOptions quick_heartbeat() {
    ServerOptions options;
    options.job_heartbeat_s = 0.05;
    return options;
  }

  void start_with_faulty_store(ServerOptions options = {}) {
    start(std::move(options), [this](const fs::path& data_dir) {
      auto store = std::make_unique<FaultyJobStore>(data_dir / "jobs.sqlite");
      faults_ = store.get();
      return store;
    });
    ASSERT_NE(faults_, nullptr);
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

  HealthStatus health(const std::string& service) { return test::serving_status(channel_, service); }
  bool wait_for_jobs_health(HealthStatus expected) {
    return test::wait_for_health(channel_, kJobsHealthService, expected);
  }
  // The server as a whole and the PoseFuse service: up whatever the job store does.
  void expect_overall_health_serving() {
    EXPECT_EQ(health(""), HealthResponse::SERVING);
    EXPECT_EQ(health(v1::PoseFuse::service_full_name()), HealthResponse::SERVING);
  }

  FaultyJobStore* faults_ = nullptr;
};

TEST_F(JobStoreFaultsTest, JobWhoseResultsCannotBeStoredFailsAndTheServerServesOn) {
  start_with_faulty_store(quick_heartbeat());
  faults_->refuse_results_after_next_claim = true;
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

TEST_F(JobStoreFaultsTest, JobsHealthIsNotServingWhileTheStoreRefusesWritesAndTheServerStaysServing) {
  start_with_faulty_store(quick_heartbeat());
  ASSERT_TRUE(wait_for_jobs_health(HealthResponse::SERVING));
  expect_overall_health_serving();

  faults_->refuse_results_after_next_claim = true;  // the disk fills up as the job runs
  v1::Job job;
  ASSERT_TRUE(submit("demo.pfchunks", job).ok());
  EXPECT_EQ(watch(job.job_id()).back().state(), v1::Job::FAILED);
  EXPECT_TRUE(wait_for_jobs_health(HealthResponse::NOT_SERVING));
  // Heartbeats later the store still refuses its probe: the jobs stay NOT_SERVING, the rest serves.
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_EQ(health(kJobsHealthService), HealthResponse::NOT_SERVING);
  expect_overall_health_serving();
  expect_serving();
  // An upload is refused before its recording is sent, naming the store's problem.
  {
    const auto call = open_upload({}, 0);
    const grpc::Status status = call->close();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE) << status.error_message();
    EXPECT_NE(status.error_message().find("the job store does not take writes now"), std::string::npos)
        << status.error_message();
    EXPECT_NE(status.error_message().find("disk is full"), std::string::npos) << status.error_message();
  }

  faults_->refuse_results = false;  // space again
  EXPECT_TRUE(wait_for_jobs_health(HealthResponse::SERVING));
  expect_overall_health_serving();
  v1::Job next;
  ASSERT_TRUE(submit("demo.pfchunks", next).ok());
  EXPECT_EQ(watch(next.job_id()).back().state(), v1::Job::SUCCEEDED);
}

// The database cannot be opened at start. A folder where the database file should be makes
// SQLite's open fail whoever runs the test: a read-only folder would not (the tests may run as
// root, whom permissions do not stop), and filling a real disk is not something a test may do.
TEST_F(JobStoreFaultsTest, ServerStartsWithAnUnopenableStoreServesFitAndOpensTheStoreOnceItCan) {
  const fs::path database = dir_ / "data" / "jobs.sqlite";
  fs::create_directories(database);
  std::ofstream(database / "in-the-way") << "x";
  ASSERT_NO_THROW(start(quick_heartbeat()));

  EXPECT_EQ(health(kJobsHealthService), HealthResponse::NOT_SERVING);
  expect_overall_health_serving();
  expect_serving();
  // Every job call answers UNAVAILABLE, naming the store and why it cannot be opened.
  const auto expect_store_unavailable = [&](const grpc::Status& status) {
    EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE) << status.error_message();
    EXPECT_NE(status.error_message().find("the job store cannot be opened"), std::string::npos)
        << status.error_message();
    EXPECT_NE(status.error_message().find(database.string()), std::string::npos) << status.error_message();
  };
  v1::Job job;
  expect_store_unavailable(submit("demo.pfchunks", job));
  {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::ListJobsResponse listing;
    expect_store_unavailable(stub_->ListJobs(&context, {}, &listing));
  }
  {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::GetJobRequest request;
    request.set_job_id("any");
    expect_store_unavailable(stub_->GetJob(&context, request, &job));
  }
  grpc::Status status;
  results("any", &status);
  expect_store_unavailable(status);

  // The obstacle goes: the next heartbeat opens the store and jobs run.
  fs::remove_all(database);
  EXPECT_TRUE(wait_for_jobs_health(HealthResponse::SERVING));
  ASSERT_TRUE(submit("demo.pfchunks", job).ok());
  EXPECT_EQ(watch(job.job_id()).back().state(), v1::Job::SUCCEEDED);
  expect_overall_health_serving();
}

}  // namespace
}  // namespace posefuse::server
