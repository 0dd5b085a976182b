// Tenants (docs/server.md "Security"): a tokens file maps each token to a tenant, every job
// belongs to the tenant that submitted it, and every job call sees only the caller's jobs; a job
// of another tenant is answered exactly like a missing one. Through the real server on
// loopback.
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "client/channel_security.hpp"
#include "tests/server/jobs_fixture.hpp"

namespace posefuse::server {
namespace {

constexpr const char* kClinicA = "0123456789abcdef0123456789abcdef";
constexpr const char* kClinicB = "fedcba9876543210fedcba9876543210";

class TenantsTest : public JobsTest {
 protected:
  void start_with_tenants() {
    std::ofstream(dir_ / "tokens") << "# token tenant\n" << kClinicA << " clinic-a\n" << kClinicB << "\tclinic-b\n";
    ServerOptions options;
    options.tokens_file = (dir_ / "tokens").string();
    start(options);
    clinic_a_ = stub_for(kClinicA);
    clinic_b_ = stub_for(kClinicB);
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

  std::unique_ptr<v1::PoseFuse::Stub> clinic_a_, clinic_b_;
};

TEST_F(TenantsTest, JobsAreSeenOnlyByTheirTenant) {
  start_with_tenants();
  v1::Job job;
  {
    grpc::ClientContext context;
    set_test_deadline(context);
    auto writer = clinic_a_->SubmitJob(&context, &job);
    v1::SubmitJobRequest request;
    request.mutable_spec()->set_recording_uri("demo.pfchunks");
    writer->Write(request);
    writer->WritesDone();
    const grpc::Status status = writer->Finish();
    ASSERT_TRUE(status.ok()) << status.error_message();
  }
  std::vector<v1::Job> states;
  ASSERT_TRUE(watch_to_end(*clinic_a_, job.job_id(), states).ok());
  ASSERT_FALSE(states.empty());
  EXPECT_EQ(states.back().state(), v1::Job::SUCCEEDED);

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

}  // namespace
}  // namespace posefuse::server
