// Job labels and listing pages are bounded (server/job_limits.hpp), so that one submitter
// cannot make `posefuse jobs` fail for everyone: through the real server on loopback.
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "server/job_limits.hpp"
#include "server/sqlite_job_store.hpp"
#include "tests/server/jobs_fixture.hpp"

namespace posefuse::server {
namespace {

TEST_F(JobsTest, LabelOverTheLimitIsInvalidArgumentNamingTheFieldAndTheLimit) {
  start();
  v1::JobSpec spec;
  spec.set_recording_uri("demo.pfchunks");
  spec.set_label(std::string(kMaxLabelBytes + 1, 'x'));
  v1::Job job;
  grpc::Status status = submit_spec(spec, job);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
  EXPECT_EQ(status.error_message().rfind("spec.label: ", 0), 0u) << status.error_message();
  EXPECT_NE(status.error_message().find("at most 256"), std::string::npos) << status.error_message();

  // An upload is refused at its spec, before any chunk is taken.
  spec.set_upload(true);
  status = submit_spec(spec, job);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
  EXPECT_EQ(status.error_message().rfind("spec.label: ", 0), 0u) << status.error_message();
  EXPECT_EQ(job_count(), 0u);

  // At the limit it is a label.
  spec.set_recording_uri("demo.pfchunks");
  spec.set_label(std::string(kMaxLabelBytes, 'x'));
  status = submit_spec(spec, job);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(job.label().size(), kMaxLabelBytes);
}

TEST_F(JobsTest, ListingPagesStayWithinTheByteLimitWhateverTheStoredJobsHold) {
  // Three failed jobs with 600 KiB error messages (more than any error of ours holds, but
  // nothing in the store bounds it), which would make one 1.8 MiB page.
  std::set<std::string> stored;
  {
    fs::create_directories(dir_ / "data");
    SqliteJobStore store(dir_ / "data" / "jobs.sqlite");
    for (int i = 0; i < 3; ++i) {
      v1::JobSpec spec;
      spec.set_recording_uri("demo.pfchunks");
      v1::Job job = store.create(spec, (dir_ / "recordings" / "demo.pfchunks").string(), "", i + 1);
      job.set_state(v1::Job::FAILED);
      job.set_error_message(std::string(600 * 1024, static_cast<char>('a' + i)));
      store.update(job);
      stored.insert(job.job_id());
    }
  }
  start();
  std::set<std::string> listed;
  std::string token;
  int pages = 0;
  do {
    grpc::ClientContext context;
    set_test_deadline(context);
    v1::ListJobsRequest request;
    request.set_page_token(token);
    v1::ListJobsResponse page;
    const grpc::Status status = stub_->ListJobs(&context, request, &page);
    ASSERT_TRUE(status.ok()) << status.error_message();
    EXPECT_LE(page.ByteSizeLong(), kMaxPageBytes);
    ASSERT_GE(page.jobs_size(), 1);
    for (const v1::Job& job : page.jobs()) listed.insert(job.job_id());
    token = page.next_page_token();
    ASSERT_LT(++pages, 10) << "the listing does not end";
  } while (!token.empty());
  EXPECT_EQ(pages, 3);  // one 600 KiB job per page
  EXPECT_EQ(listed, stored);
}

TEST_F(JobsTest, LabelStoredBeforeTheLimitIsReturnedCutAtACharacterBoundary) {
  // A 5 MiB label, stored before labels were bounded: alone more than a client receives.
  // 'x' then two-byte characters: byte 256 is inside a character, so the cut is at 255.
  std::string label = "x";
  while (label.size() < (5u << 20)) label += "\xc3\xa9";  // U+00E9
  std::string id;
  {
    fs::create_directories(dir_ / "data");
    SqliteJobStore store(dir_ / "data" / "jobs.sqlite");
    v1::JobSpec spec;
    spec.set_recording_uri("demo.pfchunks");
    spec.set_label(label);
    v1::Job job = store.create(spec, (dir_ / "recordings" / "demo.pfchunks").string(), "", 1);
    job.set_state(v1::Job::SUCCEEDED);
    store.update(job);
    id = job.job_id();
  }
  start();
  grpc::ClientContext context;
  set_test_deadline(context);
  v1::ListJobsResponse listing;
  const grpc::Status status = stub_->ListJobs(&context, {}, &listing);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(listing.jobs_size(), 1);
  EXPECT_EQ(listing.jobs(0).label(), label.substr(0, kMaxLabelBytes - 1));
  const auto states = watch(id);
  ASSERT_FALSE(states.empty());
  EXPECT_EQ(states.back().label().size(), kMaxLabelBytes - 1);
}

TEST(JobLimits, PageSizeZeroIsTheDefaultAndLargeOnesAreCut) {
  EXPECT_EQ(effective_page_size(0), kDefaultPageSize);
  EXPECT_EQ(effective_page_size(7), 7u);
  EXPECT_EQ(effective_page_size(4'000'000'000u), kMaxPageSize);
}

}  // namespace
}  // namespace posefuse::server
