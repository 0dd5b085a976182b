// Tenants (docs/server.md "Security"): a tokens file maps each token to a tenant, every job
// belongs to the tenant that submitted it, every job call sees only the caller's jobs, and a job
// by reference reads only the caller's folder of the recordings root; a job or a recording of
// another tenant is answered exactly like a missing one. Through the real server on loopback.
#include <fstream>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "client/channel_security.hpp"
#include "client/fit_call.hpp"
#include "server/session_registry.hpp"
#include "tests/server/http_client.hpp"
#include "tests/server/jobs_fixture.hpp"

namespace posefuse::server {
namespace {

constexpr const char* kClinicA = "0123456789abcdef0123456789abcdef";
constexpr const char* kClinicB = "fedcba9876543210fedcba9876543210";
constexpr const char* kClinicC = "0000111122223333444455556666777";  // a tenant without a folder
constexpr const char* kNoTenant = "99998888777766665555444433332222";

class TenantsTest : public JobsTest {
 protected:
  // The recordings root holds a folder per tenant: clinic-a's has the demo session, clinic-b's
  // is empty, clinic-c has none; the demo session also lies at the root itself.
  void start_with_tenants(ServerOptions options = {}) {
    std::ofstream(dir_ / "tokens") << "# token tenant\n"
                                   << kClinicA << " clinic-a\n"
                                   << kClinicB << "\tclinic-b\n"
                                   << kClinicC << " clinic-c\n"
                                   << kNoTenant << "\n";
    fs::create_directories(dir_ / "recordings" / "clinic-a");
    fs::create_directories(dir_ / "recordings" / "clinic-b");
    fs::copy_file(dir_ / "recordings" / "demo.pfchunks", dir_ / "recordings" / "clinic-a" / "demo.pfchunks");
    options.tokens_file = (dir_ / "tokens").string();
    start(options);
    clinic_a_ = stub_for(kClinicA);
    clinic_b_ = stub_for(kClinicB);
  }

  static grpc::Status submit_as(v1::PoseFuse::Stub& stub, const std::string& uri, v1::Job& job,
                                const std::string& label = "") {
    grpc::ClientContext context;
    set_test_deadline(context);
    auto writer = stub.SubmitJob(&context, &job);
    v1::SubmitJobRequest request;
    request.mutable_spec()->set_recording_uri(uri);
    request.mutable_spec()->set_label(label);
    writer->Write(request);
    writer->WritesDone();
    return writer->Finish();
  }

  std::unique_ptr<v1::PoseFuse::Stub> stub_for(const std::string& token) const {
    client::ChannelSecurity security;
    security.bearer_token = token;
    return v1::PoseFuse::NewStub(client::make_channel("127.0.0.1:" + std::to_string(server_->port()), security));
  }

  static grpc::Status get(v1::PoseFuse::Stub& stub, const std::string& id, v1::Job& job) {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::GetJobRequest request;
    request.set_job_id(id);
    return stub.GetJob(&context, request, &job);
  }
  static int listed(v1::PoseFuse::Stub& stub) {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::ListJobsResponse response;
    EXPECT_TRUE(stub.ListJobs(&context, {}, &response).ok());
    return response.jobs_size();
  }
  static grpc::Status watch_to_end(v1::PoseFuse::Stub& stub, const std::string& id, std::vector<v1::Job>& states) {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::WatchJobRequest request;
    request.set_job_id(id);
    grpc::Status status;
    states = posefuse::test::read_all<v1::Job>(*stub.WatchJob(&context, request), status);
    return status;
  }
  static grpc::Status results_of(v1::PoseFuse::Stub& stub, const std::string& id, std::size_t& count) {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::GetJobResultsRequest request;
    request.set_job_id(id);
    grpc::Status status;
    count = posefuse::test::read_all<v1::FitResult>(*stub.GetJobResults(&context, request), status).size();
    return status;
  }

  // Submits `uri` as the stub's tenant and watches the job to its end: its last state.
  static v1::Job run_as(v1::PoseFuse::Stub& stub, const std::string& uri, const std::string& label = "") {
    v1::Job job;
    const grpc::Status submitted = submit_as(stub, uri, job, label);
    EXPECT_TRUE(submitted.ok()) << submitted.error_message();
    std::vector<v1::Job> states;
    EXPECT_TRUE(watch_to_end(stub, job.job_id(), states).ok());
    return states.empty() ? job : states.back();
  }

  // The demo recording's whole Fit call with `token`.
  client::FitOutcome fit_as(const char* token) const {
    client::ChannelSecurity security;
    security.bearer_token = token;
    client::ResultWriter writer(dir_ / "results" / token);
    return client::run_fit(client::make_channel("127.0.0.1:" + std::to_string(server_->port()), security),
                           dir_ / "recordings" / "demo.pfchunks", writer);
  }

  std::unique_ptr<v1::PoseFuse::Stub> clinic_a_, clinic_b_;
};

TEST_F(TenantsTest, JobsAreSeenOnlyByTheirTenant) {
  start_with_tenants();
  const v1::Job job = run_as(*clinic_a_, "demo.pfchunks");
  EXPECT_EQ(job.state(), v1::Job::SUCCEEDED) << job.error_message();
  std::vector<v1::Job> states;

  // The owner sees it everywhere.
  v1::Job seen;
  EXPECT_TRUE(get(*clinic_a_, job.job_id(), seen).ok());
  EXPECT_EQ(listed(*clinic_a_), 1);
  std::size_t results = 0;
  EXPECT_TRUE(results_of(*clinic_a_, job.job_id(), results).ok());
  EXPECT_GT(results, 0u);

  // The other tenant: NOT_FOUND with the message of a job that does not exist at all.
  v1::Job none;
  const grpc::Status missing = get(*clinic_b_, "no-such-job", none);
  ASSERT_EQ(missing.error_code(), grpc::StatusCode::NOT_FOUND);
  const grpc::Status other = get(*clinic_b_, job.job_id(), none);
  EXPECT_EQ(other.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(other.error_message(), "job_id: no job '" + job.job_id() + "'");
  EXPECT_EQ(listed(*clinic_b_), 0);
  EXPECT_EQ(watch_to_end(*clinic_b_, job.job_id(), states).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(results_of(*clinic_b_, job.job_id(), results).error_code(), grpc::StatusCode::NOT_FOUND);
  {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::CancelJobRequest request;
    request.set_job_id(job.job_id());
    EXPECT_EQ(clinic_b_->CancelJob(&context, request, &none).error_code(), grpc::StatusCode::NOT_FOUND);
  }
}

TEST_F(TenantsTest, RecordingOfAnotherTenantIsAnsweredLikeAMissingOne) {
  start_with_tenants();
  // clinic-b's own folder links to clinic-a's recording and to a recording that does not exist.
  fs::create_symlink("../clinic-a/demo.pfchunks", dir_ / "recordings" / "clinic-b" / "link.pfchunks");
  fs::create_symlink("../clinic-a/none.pfchunks", dir_ / "recordings" / "clinic-b" / "dangling.pfchunks");

  // The owner runs it.
  const v1::Job job = run_as(*clinic_a_, "demo.pfchunks");
  EXPECT_EQ(job.state(), v1::Job::SUCCEEDED) << job.error_message();

  // Every way the other tenant can name it is answered as the same name of a missing recording.
  const auto expect_same = [&](v1::PoseFuse::Stub& stub, const std::string& existing, const std::string& missing,
                               grpc::StatusCode code) {
    v1::Job none;
    const grpc::Status there = submit_as(stub, existing, none);
    const grpc::Status absent = submit_as(stub, missing, none);
    EXPECT_EQ(there.error_code(), code) << existing << ": " << there.error_message();
    EXPECT_EQ(there.error_code(), absent.error_code()) << existing;
    EXPECT_EQ(there.error_message(), absent.error_message()) << existing;
    EXPECT_EQ(there.error_message().rfind("spec.recording_uri: ", 0), 0u) << there.error_message();
  };
  expect_same(*clinic_b_, "demo.pfchunks", "none.pfchunks", grpc::StatusCode::NOT_FOUND);
  expect_same(*clinic_b_, "/clinic-a/demo.pfchunks", "/clinic-a/none.pfchunks", grpc::StatusCode::NOT_FOUND);
  expect_same(*clinic_b_, "file://clinic-a/demo.pfchunks", "file://clinic-a/none.pfchunks",
              grpc::StatusCode::NOT_FOUND);
  expect_same(*clinic_b_, "../clinic-a/demo.pfchunks", "../clinic-a/none.pfchunks", grpc::StatusCode::INVALID_ARGUMENT);
  expect_same(*clinic_b_, "x/../../clinic-a/demo.pfchunks", "x/../../clinic-a/none.pfchunks",
              grpc::StatusCode::INVALID_ARGUMENT);
  expect_same(*clinic_b_, "link.pfchunks", "dangling.pfchunks", grpc::StatusCode::INVALID_ARGUMENT);
  // A tenant whose folder does not exist, and a recording at the root outside every folder.
  const auto clinic_c = stub_for(kClinicC);
  expect_same(*clinic_c, "demo.pfchunks", "none.pfchunks", grpc::StatusCode::NOT_FOUND);
  expect_same(*clinic_a_, "../demo.pfchunks", "../none.pfchunks", grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(listed(*clinic_b_), 0);
  EXPECT_EQ(listed(*clinic_c), 0);

  // A token without a tenant has no folder once tenants exist: it may upload, not name files.
  v1::Job none;
  const grpc::Status untenanted = submit_as(*stub_for(kNoTenant), "demo.pfchunks", none);
  EXPECT_EQ(untenanted.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << untenanted.error_message();
  EXPECT_EQ(untenanted.error_message().rfind("spec.recording_uri: this token has no tenant", 0), 0u)
      << untenanted.error_message();
}

TEST_F(TenantsTest, OneTenantCannotTakeEverySessionSlot) {
  // Eight slots and four tenants (clinic-a, -b, -c and the tokens without one): two each by
  // default.
  ServerOptions options;
  options.max_sessions = 8;
  start_with_tenants(options);
  const auto chunks = demo::make_demo_session();

  // clinic-a holds its two slots with streams that have sent their header.
  posefuse::test::HeldFit first(*clinic_a_, chunks[0]), second(*clinic_a_, chunks[0]);
  ASSERT_TRUE(first.sent());
  ASSERT_TRUE(second.sent());
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (server_->registry().active() != 2 && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_EQ(server_->registry().active(), 2u);

  // Its third Fit and an upload are refused, naming the per-tenant limit.
  const std::string busy =
      "tenant busy: 2 sessions and uploads of this tenant are running, its limit (--tenant-max-sessions); retry later";
  const client::FitOutcome third = fit_as(kClinicA);
  EXPECT_EQ(third.status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << third.status.error_message();
  EXPECT_EQ(third.status.error_message(), busy);
  {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::Job job;
    auto writer = clinic_a_->SubmitJob(&context, &job);
    v1::SubmitJobRequest request;
    request.mutable_spec()->set_upload(true);
    writer->Write(request);
    writer->WritesDone();
    const grpc::Status upload = writer->Finish();
    EXPECT_EQ(upload.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << upload.error_message();
    EXPECT_EQ(upload.error_message(), busy);
  }

  // Another clinic's whole session runs meanwhile.
  const client::FitOutcome other = fit_as(kClinicB);
  EXPECT_TRUE(other.status.ok()) << other.status.error_message();
  EXPECT_GT(other.results_received, 0u);

  // Once clinic-a's streams end, it is admitted again.
  EXPECT_EQ(first.cancel().error_code(), grpc::StatusCode::CANCELLED);
  EXPECT_EQ(second.cancel().error_code(), grpc::StatusCode::CANCELLED);
  ASSERT_TRUE(server_->registry().wait_for_active_at_most(0, std::chrono::seconds(30)));
  const client::FitOutcome again = fit_as(kClinicA);
  EXPECT_TRUE(again.status.ok()) << again.status.error_message();
}

// The metrics endpoint's answer once it contains `expected`, or its last answer after 30 s:
// a job's end is counted just after its watchers learn of it.
std::string scrape_until(int port, const std::string& expected) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  std::string metrics = posefuse::test::http_get(port, "/metrics");
  while (metrics.find(expected) == std::string::npos && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    metrics = posefuse::test::http_get(port, "/metrics");
  }
  return metrics;
}

TEST_F(TenantsTest, MetricsCountEachTenantAndNameNoPatient) {
  ServerOptions options;
  options.metrics_listen = "127.0.0.1:0";
  start_with_tenants(options);
  for (int i = 0; i < 2; ++i) {
    const client::FitOutcome fit = fit_as(kClinicA);
    EXPECT_TRUE(fit.status.ok()) << fit.status.error_message();
  }
  const client::FitOutcome fit = fit_as(kClinicB);
  EXPECT_TRUE(fit.status.ok()) << fit.status.error_message();
  const std::string label = "knee-patient-4711";
  EXPECT_EQ(run_as(*clinic_a_, "demo.pfchunks", label).state(), v1::Job::SUCCEEDED);
  ASSERT_TRUE(server_->registry().wait_for_active_at_most(0, std::chrono::seconds(30)));

  const std::string metrics = scrape_until(
      server_->metrics_port(), "\nposefuse_jobs_finished_total{tenant=\"clinic-a\",state=\"SUCCEEDED\"} 1\n");
  for (const char* line : {
           "posefuse_sessions_started_total 0",
           "posefuse_sessions_started_total{tenant=\"clinic-a\"} 2",
           "posefuse_sessions_started_total{tenant=\"clinic-b\"} 1",
           "posefuse_sessions_finished_total{tenant=\"clinic-a\",status=\"OK\"} 2",
           "posefuse_sessions_finished_total{tenant=\"clinic-b\",status=\"OK\"} 1",
           "posefuse_jobs_finished_total{tenant=\"clinic-a\",state=\"SUCCEEDED\"} 1",
           "posefuse_job_submits_total{tenant=\"clinic-a\",status=\"OK\"} 1",
           "posefuse_chunks_received_total 0",
           "posefuse_chunks_received_total{tenant=\"clinic-a\"} 1904",
           "posefuse_chunks_received_total{tenant=\"clinic-b\"} 952",
           "posefuse_item_errors_total 0",
       }) {
    EXPECT_NE(metrics.find("\n" + std::string(line) + "\n"), std::string::npos) << line << " in\n" << metrics;
  }
  EXPECT_EQ(metrics.find("tenant=\"clinic-c\""), std::string::npos) << "a tenant without calls has no lines";
  // Tenant names only: no token, subject id, label or path.
  for (const std::string& secret : {std::string(kClinicA), std::string(kClinicB), std::string("demo-subject"), label,
                                    std::string("demo.pfchunks"), dir_.string()}) {
    EXPECT_EQ(metrics.find(secret), std::string::npos) << secret;
  }
}

TEST(SessionSlots, TheDefaultPerTenantLimitSplitsTheSlotsEvenly) {
  EXPECT_EQ(fair_share_of_sessions(16, 0), 16u);  // no tokens file
  EXPECT_EQ(fair_share_of_sessions(16, 1), 16u);
  EXPECT_EQ(fair_share_of_sessions(16, 3), 5u);
  EXPECT_EQ(fair_share_of_sessions(2, 4), 1u);  // every tenant gets a slot
}

}  // namespace
}  // namespace posefuse::server
