// Several real posefuse-server processes (tests/server/server_process.hpp) on one PostgreSQL
// database (a private cluster, tests/server/postgres_test.hpp), with short leases: jobs
// submitted to any replica run exactly once; a replica killed with SIGKILL mid-job has its job
// finished by another after the lease expires, with the results of an uninterrupted run and no
// duplicate rows; WatchJob and CancelJob on an API replica follow and stop a job running on a
// worker; an upload to one replica runs on another; the database restarted mid-job; a database
// with a newer schema refused with a clear error.
#include <chrono>
#include <map>
#include <thread>

#include <gtest/gtest.h>

#include "client/demo_session.hpp"
#include "client/fit_call.hpp"
#include "posefuse/v1/service.grpc.pb.h"
#include "server/job_transitions.hpp"
#include "server/pg_connection.hpp"
#include "server/pg_schema.hpp"
#include "tests/server/postgres_test.hpp"
#include "tests/server/server_process.hpp"
#include "tests/server/test_support.hpp"

namespace posefuse::server {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using test::set_test_deadline;

// Long enough (about 2 s of work in a Release build) to act on a job while it runs.
constexpr double kLongSessionS = 120.0;

struct Replica {
  std::unique_ptr<test::ServerProcess> process;
  std::unique_ptr<v1::PoseFuse::Stub> stub;
};

// A results stream as bytes, without the one field that is wall time.
std::vector<std::string> comparable(std::vector<v1::FitResult> results) {
  std::vector<std::string> out;
  for (v1::FitResult& r : results) {
    if (r.has_summary()) r.mutable_summary()->clear_processing_duration_s();
    out.push_back(r.SerializeAsString());
  }
  return out;
}

class PgReplicasTest : public ::testing::Test {
 protected:
  void SetUp() override {
    cluster_ = test::start_postgres();
    if (!cluster_) return;
    conninfo_ = cluster_->conninfo(cluster_->create_database());
    fs::create_directories(dir_ / "recordings");
    demo::write_demo_session(dir_ / "recordings" / "short.pfchunks");
    demo::DemoSessionOptions long_session;
    long_session.duration_s = kLongSessionS;
    demo::write_demo_session(dir_ / "recordings" / "long.pfchunks", long_session);
  }

  // Leases: kLongLease where a takeover would be a failure (a starved worker under a sanitizer
  // build must not lose its job), kShortLease where the test waits for one to expire.
  static constexpr const char* kLongLease = "20";
  static constexpr const char* kShortLease = "2";
  std::vector<std::string> args(const std::string& name, const std::string& role, const char* lease) {
    return {"--listen",
            "127.0.0.1:0",
            "--workers",
            "2",
            "--max-jobs",
            "1",
            "--data-dir",
            (dir_ / name).string(),
            "--recordings-root",
            (dir_ / "recordings").string(),
            "--job-store",
            conninfo_,
            "--role",
            role,
            "--job-lease-s",
            lease,
            "--job-heartbeat-s",
            "0.25",
            "--shutdown-grace-s",
            "1"};
  }
  Replica start(const std::string& name, const std::string& role = "both", const char* lease = kLongLease,
                const std::vector<std::string>& extra = {}) {
    Replica replica;
    std::vector<std::string> all = args(name, role, lease);
    all.insert(all.end(), extra.begin(), extra.end());
    replica.process = std::make_unique<test::ServerProcess>(POSEFUSE_SERVER_BINARY, all, dir_ / (name + ".log"));
    const int port = replica.process->port();
    replica.stub = v1::PoseFuse::NewStub(client::make_channel("127.0.0.1:" + std::to_string(port)));
    return replica;
  }

  static v1::Job submit(Replica& replica, const std::string& uri) {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::Job job;
    auto writer = replica.stub->SubmitJob(&context, &job);
    v1::SubmitJobRequest request;
    request.mutable_spec()->set_recording_uri(uri);
    writer->Write(request);
    writer->WritesDone();
    const grpc::Status status = writer->Finish();
    EXPECT_TRUE(status.ok()) << status.error_message();
    return job;
  }
  static v1::Job get(Replica& replica, const std::string& id) {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::GetJobRequest request;
    request.set_job_id(id);
    v1::Job job;
    const grpc::Status status = replica.stub->GetJob(&context, request, &job);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return job;
  }
  // Polls until the job has processed some chunks (it is running somewhere).
  static void wait_running(Replica& replica, const std::string& id) {
    const auto deadline = std::chrono::steady_clock::now() + 60s;
    while (std::chrono::steady_clock::now() < deadline) {
      const v1::Job job = get(replica, id);
      ASSERT_FALSE(job.state() != v1::Job::QUEUED && job.state() != v1::Job::RUNNING)
          << "the job ended before the test could act on it: " << v1::Job::State_Name(job.state());
      if (job.state() == v1::Job::RUNNING && job.progress().chunks_processed() > 0) return;
      std::this_thread::sleep_for(10ms);
    }
    FAIL() << "job " << id << " never ran";
  }
  // Every state WatchJob reports until the end.
  static std::vector<v1::Job> watch(Replica& replica, const std::string& id) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + 120s);
    v1::WatchJobRequest request;
    request.set_job_id(id);
    grpc::Status status;
    auto states = test::read_all<v1::Job>(*replica.stub->WatchJob(&context, request), status);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return states;
  }
  static std::vector<v1::FitResult> results(Replica& replica, const std::string& id) {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::GetJobResultsRequest request;
    request.set_job_id(id);
    grpc::Status status;
    auto all = test::read_all<v1::FitResult>(*replica.stub->GetJobResults(&context, request), status);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return all;
  }
  // One number from `sql`, with `job_id` as $1 when it is not empty.
  std::int64_t sql_int(const std::string& sql, const std::string& job_id) {
    PgConnection connection(conninfo_);
    PgResult row = job_id.empty() ? connection.exec(sql) : connection.exec(sql, {pg_text(job_id)});
    return PQntuples(row.get()) == 0 ? -1 : pg_int64(row.get(), 0, 0);
  }
  std::int64_t attempts(const std::string& id) { return sql_int("SELECT attempts FROM jobs WHERE id = $1", id); }
  std::int64_t result_rows(const std::string& id) {
    return sql_int("SELECT count(*) FROM results WHERE job_id = $1", id);
  }
  static std::size_t count(const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
  }

  test::TempDir temp_;
  const fs::path& dir_ = temp_.path();
  std::unique_ptr<test::PostgresCluster> cluster_;
  std::string conninfo_;
};

TEST_F(PgReplicasTest, JobsSubmittedToAnyReplicaRunExactlyOnce) {
  std::vector<Replica> replicas;
  for (const char* name : {"a", "b", "c"}) replicas.push_back(start(name));
  std::vector<std::string> ids;
  for (int i = 0; i < 9; ++i) ids.push_back(submit(replicas[i % 3], "short.pfchunks").job_id());
  std::vector<std::string> reference;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    // Watched on another replica than the one it was submitted to.
    const auto states = watch(replicas[(i + 1) % 3], ids[i]);
    ASSERT_FALSE(states.empty());
    EXPECT_EQ(states.back().state(), v1::Job::SUCCEEDED) << states.back().error_message();
    EXPECT_EQ(attempts(ids[i]), 1);
    const auto all = comparable(results(replicas[(i + 2) % 3], ids[i]));
    if (i == 0) reference = all;
    EXPECT_TRUE(all == reference) << "job " << i << " results differ";
    EXPECT_EQ(result_rows(ids[i]), static_cast<std::int64_t>(reference.size()));
  }
  std::string logs;
  for (Replica& r : replicas) EXPECT_EQ(r.process->terminate(), 0);
  for (Replica& r : replicas) logs += r.process->log();
  for (const std::string& id : ids) {
    EXPECT_EQ(count(logs, "event=job_claimed job=" + id), 1u) << id;
    EXPECT_EQ(count(logs, "event=job_end job=" + id + " state=SUCCEEDED"), 1u) << id;
  }
}

TEST_F(PgReplicasTest, AKilledReplicasJobIsFinishedByAnotherAfterItsLeaseWithTheSameResults) {
  Replica a = start("a", "both", kShortLease);
  const std::string id = submit(a, "long.pfchunks").job_id();
  wait_running(a, id);
  // Killed before the other replica starts, so that a slow start cannot leave it time to finish.
  a.process->kill9();
  const auto killed_at = std::chrono::steady_clock::now();
  Replica b = start("b", "both", kShortLease);
  const auto states = watch(b, id);
  ASSERT_FALSE(states.empty());
  EXPECT_EQ(states.back().state(), v1::Job::SUCCEEDED) << states.back().error_message();
  const std::string b_log = b.process->log();
  EXPECT_EQ(count(b_log, "event=job_lease_expired job=" + id + " state=QUEUED"), 1u) << b_log;
  EXPECT_EQ(count(b_log, "event=job_claimed job=" + id + " attempt=2"), 1u) << b_log;
  EXPECT_EQ(attempts(id), 2);
  std::cout << "lease takeover and rerun after kill -9: "
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - killed_at).count() << " s\n";

  // The same recording uninterrupted on one node: the same results, row for row.
  const std::string single = submit(b, "long.pfchunks").job_id();
  EXPECT_EQ(watch(b, single).back().state(), v1::Job::SUCCEEDED);
  const auto taken_over = comparable(results(b, id));
  const auto reference = comparable(results(b, single));
  ASSERT_FALSE(reference.empty());
  EXPECT_TRUE(taken_over == reference) << taken_over.size() << " vs " << reference.size() << " results";
  EXPECT_EQ(result_rows(id), static_cast<std::int64_t>(reference.size()));
}

TEST_F(PgReplicasTest, WatchAndCancelOnAnApiReplicaFollowAndStopAJobOnAWorker) {
  Replica worker = start("worker", "worker");
  Replica api = start("api", "api");
  {
    // A worker serves no API calls (health only), so that Kubernetes scales the roles apart.
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::ServerInfo info;
    const grpc::Status status = worker.stub->GetServerInfo(&context, {}, &info);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << status.error_message();
  }
  // Followed: progress from the worker reaches a watcher on the API replica. The long recording,
  // because a watcher reads the state a notification points at, and a short job can be done
  // before its first notification is read.
  const std::string watched = submit(api, "long.pfchunks").job_id();
  const auto states = watch(api, watched);
  ASSERT_GE(states.size(), 3u);
  EXPECT_EQ(states.back().state(), v1::Job::SUCCEEDED);
  std::size_t with_progress = 0;
  for (const v1::Job& s : states) with_progress += s.state() == v1::Job::RUNNING && s.progress().chunks_processed() > 0;
  EXPECT_GT(with_progress, 0u);

  // Stopped: a cancel on the API replica ends the run on the worker.
  const std::string id = submit(api, "long.pfchunks").job_id();
  std::vector<v1::Job> cancel_states;
  std::thread watcher([&] { cancel_states = watch(api, id); });
  wait_running(api, id);
  {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::CancelJobRequest request;
    request.set_job_id(id);
    v1::Job answer;
    ASSERT_TRUE(api.stub->CancelJob(&context, request, &answer).ok());
  }
  watcher.join();
  ASSERT_FALSE(cancel_states.empty());
  EXPECT_EQ(cancel_states.back().state(), v1::Job::CANCELLED);
  EXPECT_EQ(get(api, id).state(), v1::Job::CANCELLED);
  EXPECT_LT(cancel_states.back().progress().chunks_processed(), 10000u);  // stopped mid-way
  EXPECT_EQ(worker.process->terminate(), 0);
  EXPECT_EQ(count(worker.process->log(), "event=job_end job=" + id + " state=CANCELLED"), 1u);
}

TEST_F(PgReplicasTest, AnUploadedJobWhoseLeasesRunOutFailsWithAClearErrorAndLeavesNoUpload) {
  const std::vector<std::string> one_attempt{"--job-max-attempts", "1"};
  Replica a = start("a", "both", kShortLease, one_attempt);
  v1::Job job;
  {
    grpc::ClientContext context;
    set_test_deadline(context);
    auto writer = a.stub->SubmitJob(&context, &job);
    v1::SubmitJobRequest request;
    request.mutable_spec()->set_upload(true);
    writer->Write(request);
    demo::DemoSessionOptions long_session;
    long_session.duration_s = kLongSessionS;
    for (const v1::SessionChunk& chunk : demo::make_demo_session(long_session)) {
      *request.mutable_chunk() = chunk;
      writer->Write(request);
    }
    writer->WritesDone();
    const grpc::Status status = writer->Finish();
    ASSERT_TRUE(status.ok()) << status.error_message();
  }
  wait_running(a, job.job_id());
  Replica b = start("b", "both", kShortLease, one_attempt);
  a.process->kill9();
  const auto states = watch(b, job.job_id());
  ASSERT_FALSE(states.empty());
  const v1::Job& failed = states.back();
  EXPECT_EQ(failed.state(), v1::Job::FAILED);
  EXPECT_EQ(failed.error_code(), static_cast<int>(grpc::StatusCode::ABORTED));
  EXPECT_EQ(failed.error_message().rfind("job: its worker's lease expired 1 time (", 0), 0u) << failed.error_message();
  EXPECT_EQ(b.process->terminate(), 0);
  EXPECT_EQ(sql_int("SELECT count(*) FROM uploads", ""), 0);
}

TEST_F(PgReplicasTest, AnUploadToOneReplicaRunsOnAnotherWithTheResultsOfTheSameRecordingByReference) {
  Replica worker = start("worker", "worker");
  Replica api = start("api", "api");
  v1::Job uploaded;
  {
    grpc::ClientContext context;
    set_test_deadline(context);
    auto writer = api.stub->SubmitJob(&context, &uploaded);
    v1::SubmitJobRequest request;
    request.mutable_spec()->set_upload(true);
    writer->Write(request);
    for (const v1::SessionChunk& chunk : demo::make_demo_session()) {
      *request.mutable_chunk() = chunk;
      writer->Write(request);
    }
    writer->WritesDone();
    const grpc::Status status = writer->Finish();
    ASSERT_TRUE(status.ok()) << status.error_message();
  }
  EXPECT_EQ(watch(api, uploaded.job_id()).back().state(), v1::Job::SUCCEEDED);
  const std::string by_reference = submit(api, "short.pfchunks").job_id();
  EXPECT_EQ(watch(api, by_reference).back().state(), v1::Job::SUCCEEDED);
  EXPECT_TRUE(comparable(results(api, uploaded.job_id())) == comparable(results(api, by_reference)));
  // Nothing of the upload stays behind once its job has finished: not in the database, not in
  // either replica's folder.
  EXPECT_EQ(worker.process->terminate(), 0);
  EXPECT_EQ(sql_int("SELECT count(*) FROM uploads", ""), 0);
  for (const char* folder : {"api/uploads", "worker/uploads", "worker/fetched"}) {
    EXPECT_TRUE(fs::is_empty(dir_ / folder)) << folder;
  }
}

TEST_F(PgReplicasTest, AJobRunningWhenTheDatabaseRestartsFinishesWithTheSameResults) {
  Replica a = start("a", "both", kShortLease);
  const std::string id = submit(a, "long.pfchunks").job_id();
  wait_running(a, id);
  cluster_->stop();  // as a crash
  std::this_thread::sleep_for(500ms);
  cluster_->start();
  const auto deadline = std::chrono::steady_clock::now() + 120s;
  v1::Job job;
  while (std::chrono::steady_clock::now() < deadline) {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::GetJobRequest request;
    request.set_job_id(id);
    if (a.stub->GetJob(&context, request, &job).ok() && is_terminal(job.state())) break;
    std::this_thread::sleep_for(50ms);
  }
  EXPECT_EQ(job.state(), v1::Job::SUCCEEDED) << job.error_message();
  const std::string single = submit(a, "long.pfchunks").job_id();
  EXPECT_EQ(watch(a, single).back().state(), v1::Job::SUCCEEDED);
  EXPECT_TRUE(comparable(results(a, id)) == comparable(results(a, single)));
  EXPECT_EQ(result_rows(id), result_rows(single));
  // A run whose write failed while the database was away stopped writing; a second attempt
  // ran the job from the beginning once the lease ran out (or at once, had the hand-back
  // reached the database, which then does not count the first attempt). A run that wrote
  // nothing during the outage (its thread had no CPU then) just went on.
  const std::string log = a.process->log();
  const bool abandoned = count(log, "event=job_abandoned job=" + id + " reason=job_store_unavailable") == 1;
  const bool handed_back = count(log, "event=job_handed_back job=" + id) == 1;
  EXPECT_EQ(attempts(id), abandoned && !handed_back ? 2 : 1) << log;
  EXPECT_TRUE(abandoned || count(log, "event=job_claimed job=" + id) == 1) << log;
}

TEST_F(PgReplicasTest, ADatabaseWithANewerSchemaIsRefusedAtStartWithAClearError) {
  {
    Replica first = start("a");  // migrates
    EXPECT_EQ(first.process->terminate(), 0);
  }
  {
    PgConnection admin(conninfo_);
    admin.exec("UPDATE posefuse_schema SET version = $1", {pg_int(pg_schema_version() + 1)});
  }
  test::ServerProcess refused(POSEFUSE_SERVER_BINARY, args("b", "both", kLongLease), dir_ / "refused.log");
  EXPECT_EQ(refused.wait_exit(), 2);
  const std::string log = refused.log();
  EXPECT_NE(log.find("posefuse-server: --job-store: the database's posefuse schema is version " +
                     std::to_string(pg_schema_version() + 1) + ", newer than this posefuse-server knows"),
            std::string::npos)
      << log;
}

}  // namespace
}  // namespace posefuse::server
