// Batch jobs through the real server: submit by reference, watch, results, listing, errors, and
// a job left RUNNING by a stopped server that the next server completes.
#include <filesystem>
#include <fstream>
#include <thread>

#include <gtest/gtest.h>

#include "client/demo_session.hpp"
#include "client/fit_call.hpp"
#include "posefuse/v1/service.grpc.pb.h"
#include "server/job_limits.hpp"
#include "server/posefuse_server.hpp"
#include "server/sqlite_job_store.hpp"
#include "session/chunk_file.hpp"
#include "tests/server/faulty_job_store.hpp"
#include "tests/server/jobs_fixture.hpp"
#include "tests/server/test_support.hpp"

namespace posefuse::server {
namespace {

using test::orientation_samples;

// A job of the demo recording in `state` with `results`, written to the data dir's SQLite store
// before any server runs (as a stopped server leaves it); returns its id.
std::string store_demo_job(const fs::path& dir, v1::Job::State state, const std::vector<v1::FitResult>& results) {
  fs::create_directories(dir / "data");
  SqliteJobStore store(dir / "data" / "jobs.sqlite");
  v1::JobSpec spec;
  spec.set_recording_uri("demo.pfchunks");
  v1::Job job = store.create(spec, (dir / "recordings" / "demo.pfchunks").string(), "", 1);
  job.set_state(state);
  store.update(job);
  store.append_results(job.job_id(), results);
  return job.job_id();
}

TEST_F(JobsTest, SubmittedJobRunsToSucceededWithEveryResult) {
  start();
  v1::Job job;
  const grpc::Status status = submit("demo.pfchunks", job);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_FALSE(job.job_id().empty());
  EXPECT_EQ(job.label(), "test");

  const std::vector<v1::Job> states = watch(job.job_id());
  ASSERT_FALSE(states.empty());
  EXPECT_EQ(states.back().state(), v1::Job::SUCCEEDED);
  EXPECT_EQ(states.back().summary().depth_frames(), 300u);

  const auto all = results(job.job_id());
  const auto samples = orientation_samples(all);
  EXPECT_EQ(samples.at(demo::kArmDevice), 800u);
  EXPECT_EQ(samples.at(demo::kBaseDevice), 800u);
  ASSERT_FALSE(all.empty());
  EXPECT_TRUE(all.back().has_summary());

  grpc::ClientContext context;
  set_test_deadline(context);
  v1::ListJobsResponse listing;
  ASSERT_TRUE(stub_->ListJobs(&context, {}, &listing).ok());
  ASSERT_EQ(listing.jobs_size(), 1);
  EXPECT_EQ(listing.jobs(0).job_id(), job.job_id());
  EXPECT_TRUE(listing.next_page_token().empty());
}

TEST_F(JobsTest, BadSubmissionsNameTheField) {
  start();
  v1::Job job;
  grpc::Status status = submit("../outside.pfchunks", job);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
  EXPECT_EQ(status.error_message().rfind("spec.recording_uri", 0), 0u);
  status = submit("missing.pfchunks", job);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND) << status.error_message();

  grpc::ClientContext context;
  set_test_deadline(context);
  v1::CancelJobRequest cancel;
  cancel.set_job_id("no-such-job");
  EXPECT_EQ(stub_->CancelJob(&context, cancel, &job).error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST_F(JobsTest, JobWithBadRecordingFailsWithTheField) {
  // A chunk file that is a truncated demo session: no end marker.
  {
    const auto chunks = demo::make_demo_session();
    session::ChunkFileWriter out(dir_ / "recordings" / "truncated.pfchunks");
    for (std::size_t i = 0; i + 1 < chunks.size(); ++i) out.write(chunks[i]);
    out.finish();
  }
  start();
  v1::Job job;
  ASSERT_TRUE(submit("truncated.pfchunks", job).ok());
  const auto states = watch(job.job_id());
  ASSERT_FALSE(states.empty());
  EXPECT_EQ(states.back().state(), v1::Job::FAILED);
  EXPECT_EQ(states.back().error_code(), static_cast<int>(grpc::StatusCode::INVALID_ARGUMENT));
  EXPECT_EQ(states.back().error_message().rfind("end: ", 0), 0u) << states.back().error_message();
}

TEST_F(JobsTest, JobLeftRunningByAStoppedServerCompletesAfterRestart) {
  // What a server killed mid-job leaves behind: the job RUNNING with partial results.
  v1::FitResult partial;
  partial.mutable_progress()->set_chunks_processed(64);
  const std::string id = store_demo_job(dir_, v1::Job::RUNNING, {partial});
  start();
  const auto states = watch(id);
  ASSERT_FALSE(states.empty());
  EXPECT_EQ(states.back().state(), v1::Job::SUCCEEDED);
  const auto all = results(id);
  // Restarted from the beginning: the partial results were replaced, nothing is doubled.
  EXPECT_EQ(orientation_samples(all).at(demo::kArmDevice), 800u);
  std::size_t summaries = 0;
  for (const auto& r : all) summaries += r.has_summary();
  EXPECT_EQ(summaries, 1u);
}

TEST_F(JobsTest, UploadedJobRunsToSucceededWithEveryResultAndDropsItsSpoolFile) {
  start();
  v1::Job job;
  const grpc::Status status = upload(demo::make_demo_session(), job);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(job.label(), "uploaded");
  EXPECT_TRUE(job.recording_uri().empty());
  const auto states = watch(job.job_id());
  ASSERT_FALSE(states.empty());
  EXPECT_EQ(states.back().state(), v1::Job::SUCCEEDED);
  EXPECT_EQ(states.back().summary().depth_frames(), 300u);
  const auto samples = orientation_samples(results(job.job_id()));
  EXPECT_EQ(samples.at(demo::kArmDevice), 800u);
  EXPECT_EQ(samples.at(demo::kBaseDevice), 800u);
  // The spooled copy is gone once its worker has finished the job (its results are in the
  // store); WatchJob may report the end just before.
  ASSERT_TRUE(server_->jobs()->wait_idle(std::chrono::seconds(30)));
  EXPECT_EQ(files_in_spool(), 0u);
}

TEST_F(JobsTest, UploadWithBadDataChunksIsAcceptedAndTheJobReportsThemAsFitWould) {
  start();
  auto chunks = demo::make_demo_session();
  for (auto& chunk : chunks) {
    if (chunk.has_depth()) {
      chunk.mutable_depth()->set_width(63);  // the first depth frame only
      break;
    }
  }
  v1::Job job;
  ASSERT_TRUE(upload(chunks, job).ok());
  EXPECT_EQ(watch(job.job_id()).back().state(), v1::Job::SUCCEEDED);
  std::vector<v1::ItemError> errors;
  for (const auto& r : results(job.job_id())) {
    if (r.has_item_error()) errors.push_back(r.item_error());
  }
  // The bad frame, then the end marker whose depth count includes it (as Fit reports them).
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_NE(errors[0].field().find("depth.width"), std::string::npos) << errors[0].field();
  EXPECT_NE(errors[1].field().find("end.depth_frames"), std::string::npos) << errors[1].field();
}

TEST_F(JobsTest, TruncatedUploadIsInvalidArgumentAndLeavesNoJobAndNoFile) {
  start();
  auto chunks = demo::make_demo_session();
  chunks.resize(chunks.size() / 2);  // the client stops half way, without the end marker
  v1::Job job;
  const grpc::Status status = upload(chunks, job);
  expect_refused(status, grpc::StatusCode::INVALID_ARGUMENT, "end: ");
  EXPECT_NE(status.error_message().find("truncated"), std::string::npos);
}

TEST_F(JobsTest, OversizedUploadIsResourceExhaustedAndLeavesNoJobAndNoFile) {
  ServerOptions options;
  options.max_upload_mb = 0.25;  // the demo session is about 0.5 MiB
  start(options);
  v1::Job job;
  const grpc::Status status = upload(demo::make_demo_session(), job);
  expect_refused(status, grpc::StatusCode::RESOURCE_EXHAUSTED, "upload: ");
  EXPECT_NE(status.error_message().find("--max-upload-mb"), std::string::npos);
}

// Two uploads at once that the spool quota cannot hold together: the one whose chunk would pass
// it is refused, naming the flag, and leaves nothing; the other becomes a job and runs; once it
// has given its bytes back the next upload fits.
TEST_F(JobsTest, SpoolQuotaRefusesTheUploadThatWouldPassItAndTheOthersGoOn) {
  const auto chunks = demo::make_demo_session();
  std::uint64_t session_bytes = 0;  // as the spool counts them (upload_spool.cpp)
  for (const auto& chunk : chunks) session_bytes += chunk.ByteSizeLong() + 10;
  ServerOptions options;
  options.max_spool_mb = 1.5 * static_cast<double>(session_bytes) / (1024.0 * 1024.0);
  start(options);

  // The first upload holds everything but its end marker, reserved in the quota.
  const auto first = open_upload(chunks, chunks.size() - 1);
  const std::uint64_t held = session_bytes - (chunks.back().ByteSizeLong() + 10);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (server_->spool_quota().in_use() < held && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_EQ(server_->spool_quota().in_use(), held);

  v1::Job refused;
  const grpc::Status status = upload(chunks, refused);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << status.error_message();
  EXPECT_EQ(status.error_message().rfind("upload: the uploads in transit together would pass", 0), 0u)
      << status.error_message();
  EXPECT_NE(status.error_message().find("(--max-spool-mb)"), std::string::npos) << status.error_message();
  EXPECT_EQ(server_->spool_quota().in_use(), held);  // the refused upload gave its bytes back
  EXPECT_EQ(files_in_spool(), 1u);                   // the first upload's, nothing of the refused one

  // The first upload is untouched: it completes and runs.
  ASSERT_TRUE(first->send(chunks.back()));
  const grpc::Status completed = first->close();
  ASSERT_TRUE(completed.ok()) << completed.error_message();
  EXPECT_EQ(watch(first->job.job_id()).back().state(), v1::Job::SUCCEEDED);
  EXPECT_EQ(server_->spool_quota().in_use(), 0u);

  v1::Job again;
  const grpc::Status retried = upload(chunks, again);
  ASSERT_TRUE(retried.ok()) << retried.error_message();
  EXPECT_EQ(watch(again.job_id()).back().state(), v1::Job::SUCCEEDED);
  EXPECT_EQ(job_count(), 2u);
}

TEST_F(JobsTest, UploadsThatCannotBeASessionAreInvalidArgumentNamingTheField) {
  start();
  const auto chunks = demo::make_demo_session();
  v1::Job job;
  // No header first.
  grpc::Status status = upload({chunks.begin() + 1, chunks.end()}, job);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message().rfind("chunk[0]", 0), 0u) << status.error_message();
  // A chunk after the end marker.
  auto extra = chunks;
  extra.push_back(chunks[1]);
  status = upload(extra, job);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(status.error_message().rfind("chunk[" + std::to_string(chunks.size()) + "]", 0), 0u)
      << status.error_message();
  // A second spec instead of a chunk.
  {
    grpc::ClientContext context;
    set_test_deadline(context);
    auto writer = stub_->SubmitJob(&context, &job);
    v1::SubmitJobRequest request;
    request.mutable_spec()->set_upload(true);
    writer->Write(request);
    writer->Write(request);
    writer->WritesDone();
    status = writer->Finish();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_EQ(status.error_message().rfind("chunk[0]: ", 0), 0u) << status.error_message();
  }
  EXPECT_EQ(job_count(), 0u);
  EXPECT_EQ(files_in_spool(), 0u);
}

TEST_F(JobsTest, SilentUploadEndsWithDeadlineExceededAndLeavesNothing) {
  ServerOptions options;
  options.idle_timeout_s = 0.3;
  start(options);
  const auto call = open_upload(demo::make_demo_session(), 3);
  // Then nothing: the server ends the call after the idle timeout (Finish waits for it).
  expect_refused(call->writer->Finish(), grpc::StatusCode::DEADLINE_EXCEEDED, "no message");
  EXPECT_TRUE(server_->registry().wait_for_active_at_most(0, std::chrono::seconds(30)));
}

TEST_F(JobsTest, AnUploadTakesASessionSlot) {
  ServerOptions options;
  options.max_sessions = 1;
  start(options);
  const auto chunks = demo::make_demo_session();
  const auto first = open_upload(chunks, 1);
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (server_->registry().active() != 1 && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_EQ(server_->registry().active(), 1u);
  // The slot is taken: a second upload is refused at once.
  v1::Job other;
  const grpc::Status refused = upload(chunks, other);
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << refused.error_message();
  // The first upload goes on and completes; its slot is freed.
  for (std::size_t i = 1; i < chunks.size(); ++i) ASSERT_TRUE(first->send(chunks[i]));
  const grpc::Status status = first->close();
  ASSERT_TRUE(status.ok()) << status.error_message();
  const v1::Job& job = first->job;
  EXPECT_EQ(watch(job.job_id()).back().state(), v1::Job::SUCCEEDED);
  EXPECT_TRUE(server_->registry().wait_for_active_at_most(0, std::chrono::seconds(30)));
}

TEST_F(JobsTest, UploadedJobLeftRunningCompletesAfterRestartAndPartialUploadsAreRemoved) {
  // What a server killed mid-job leaves behind: an uploaded job RUNNING with its spooled chunk
  // file, and the partial file of an upload that was still arriving.
  const fs::path spool = dir_ / "data" / "uploads";
  fs::create_directories(spool);
  demo::write_demo_session(spool / "a.pfchunks");
  std::ofstream(spool / "b.pfchunks.partial") << "the first bytes of an upload";
  std::string id;
  {
    SqliteJobStore store(dir_ / "data" / "jobs.sqlite");
    v1::JobSpec spec;
    spec.set_upload(true);
    v1::Job job = store.create(spec, (spool / "a.pfchunks").string(), "", 1);
    id = job.job_id();
    job.set_state(v1::Job::RUNNING);
    store.update(job);
  }
  start();
  EXPECT_FALSE(fs::exists(spool / "b.pfchunks.partial"));
  const auto states = watch(id);
  ASSERT_FALSE(states.empty());
  EXPECT_EQ(states.back().state(), v1::Job::SUCCEEDED);
  EXPECT_EQ(orientation_samples(results(id)).at(demo::kArmDevice), 800u);
  ASSERT_TRUE(server_->jobs()->wait_idle(std::chrono::seconds(30)));
  EXPECT_EQ(files_in_spool(), 0u);
}

TEST_F(JobsTest, ResultsOfAnUnknownJobAreNotFound) {
  start();
  grpc::Status status;
  results("nope", &status);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND);
}

// A finished job with more results than one page: GetJobResults streams every one, in order,
// reading the store a bounded page at a time (never all of them at once).
TEST_F(JobsTest, ResultsAreStreamedFromTheStoreInBoundedPagesCompleteAndInOrder) {
  constexpr std::size_t kResults = 3 * kResultsPageSize + 5;
  std::vector<v1::FitResult> stored(kResults);
  for (std::size_t i = 0; i < kResults; ++i) stored[i].mutable_progress()->set_chunks_processed(i);
  const std::string id = store_demo_job(dir_, v1::Job::SUCCEEDED, stored);
  FaultyJobStore* store = nullptr;
  start({}, [&store](const fs::path& data_dir) {
    auto counting = std::make_unique<FaultyJobStore>(data_dir / "jobs.sqlite");
    store = counting.get();
    return counting;
  });
  grpc::Status status;
  const auto all = results(id, &status);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(all.size(), kResults);
  for (std::size_t i = 0; i < kResults; ++i) EXPECT_EQ(all[i].progress().chunks_processed(), i) << "result " << i;
  EXPECT_LE(store->largest_results_page.load(), kResultsPageSize);
  EXPECT_GE(store->results_reads.load(), kResults / kResultsPageSize);
}

}  // namespace
}  // namespace posefuse::server
