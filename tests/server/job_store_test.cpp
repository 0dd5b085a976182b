// SqliteJobStore: jobs and results survive closing and reopening the database (a server
// restart), listing pages newest first, a job left RUNNING is queued again by the first reap.
// The queue contract shared with PostgreSQL: job_store_contract_test.cpp.
#include <filesystem>
#include <optional>

#include <gtest/gtest.h>

#include <sqlite3.h>

#include "common/error.hpp"
#include "server/job_store_errors.hpp"
#include "server/sqlite_job_store.hpp"
#include "tests/server/test_support.hpp"

namespace posefuse::server {
namespace {

namespace fs = std::filesystem;

std::string hex(const std::string& bytes) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string out;
  for (const char c : bytes) {
    out += kDigits[static_cast<unsigned char>(c) >> 4];
    out += kDigits[static_cast<unsigned char>(c) & 0xF];
  }
  return out;
}

class JobStoreTest : public ::testing::Test {
 protected:
  fs::path db() const { return dir_ / "jobs.sqlite"; }

  static v1::JobSpec spec(const std::string& label) {
    v1::JobSpec s;
    s.set_label(label);
    s.set_recording_uri(label + ".pfchunks");
    return s;
  }

  test::TempDir temp_;
  const fs::path& dir_ = temp_.path();
};

TEST_F(JobStoreTest, JobsAndResultsSurviveReopening) {
  std::string id;
  {
    SqliteJobStore store(db());
    v1::Job job = store.create(spec("a"), "/recordings/a.pfchunks", "", 1000);
    id = job.job_id();
    EXPECT_EQ(job.state(), v1::Job::QUEUED);
    job.set_state(v1::Job::RUNNING);
    job.mutable_progress()->set_chunks_processed(64);
    store.update(job);
    v1::FitResult progress, summary;
    progress.mutable_progress()->set_chunks_processed(64);
    summary.mutable_summary()->set_chunks(100);
    store.append_results(id, {progress});
    store.append_results(id, {summary});
  }
  SqliteJobStore reopened(db());
  const auto record = reopened.get(id);
  ASSERT_TRUE(record);
  EXPECT_EQ(record->job.state(), v1::Job::RUNNING);
  EXPECT_EQ(record->job.progress().chunks_processed(), 64u);
  EXPECT_EQ(record->job.recording_uri(), "a.pfchunks");
  EXPECT_EQ(record->recording_path, "/recordings/a.pfchunks");
  const auto results = reopened.results(id, 0, 1000);
  ASSERT_EQ(results.size(), 2u);
  EXPECT_TRUE(results[0].has_progress());
  EXPECT_EQ(results[1].summary().chunks(), 100u);
  // The process that ran it is gone: the first reap queues it again without its results.
  const auto reaped = reopened.reap(3, 2000);
  ASSERT_EQ(reaped.size(), 1u);
  EXPECT_EQ(reaped[0].job_id, id);
  EXPECT_EQ(reaped[0].state, v1::Job::QUEUED);
  EXPECT_EQ(reopened.get(id)->job.state(), v1::Job::QUEUED);
  EXPECT_TRUE(reopened.results(id, 0, 1000).empty());
}

TEST_F(JobStoreTest, ListsNewestFirstWithPagesAndStateFilter) {
  SqliteJobStore store(db());
  std::vector<std::string> ids;
  for (int i = 0; i < 5; ++i) ids.push_back(store.create(spec("j" + std::to_string(i)), "p", "", i).job_id());
  v1::Job done = store.get(ids[1])->job;
  done.set_state(v1::Job::SUCCEEDED);
  store.update(done);

  const auto first_page = store.list(2, "", {}, "");
  ASSERT_EQ(first_page.size(), 2u);
  EXPECT_EQ(first_page[0].job_id(), ids[4]);
  EXPECT_EQ(first_page[1].job_id(), ids[3]);
  const auto second_page = store.list(2, first_page.back().job_id(), {}, "");
  ASSERT_EQ(second_page.size(), 2u);
  EXPECT_EQ(second_page[0].job_id(), ids[2]);
  const auto succeeded = store.list(10, "", {v1::Job::SUCCEEDED}, "");
  ASSERT_EQ(succeeded.size(), 1u);
  EXPECT_EQ(succeeded[0].job_id(), ids[1]);
  EXPECT_EQ(store.list(10, "", {v1::Job::QUEUED}, "").size(), 4u);
  EXPECT_FALSE(store.get("no-such-job"));
}

TEST_F(JobStoreTest, UpdatingAnUnknownJobIsNotFound) {
  SqliteJobStore store(db());
  v1::Job job;
  job.set_job_id("missing");
  try {
    store.update(job);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kNotFound);
  }
}

TEST_F(JobStoreTest, ASecondOpeningOfTheSameFileIsRefusedUntilTheFirstCloses) {
  std::optional<SqliteJobStore> first(std::in_place, db());
  try {
    SqliteJobStore second(db());
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kFailedPrecondition);
    EXPECT_NE(std::string(e.what()).find("another posefuse-server process uses this job store"), std::string::npos)
        << e.what();
    // Never passes by waiting: a server does not start on it (DeferredJobStore).
    EXPECT_NE(dynamic_cast<const StoreMisconfigured*>(&e), nullptr);
  }
  first.reset();
  SqliteJobStore reopened(db());
}

TEST_F(JobStoreTest, UnopenableDatabaseIsFailedPrecondition) {
  try {
    SqliteJobStore store(dir_ / "no" / "such" / "dir" / "jobs.sqlite");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kFailedPrecondition);
  }
}

TEST_F(JobStoreTest, ListsOnlyTheOwnersJobsAndKeepsEachJobsOwner) {
  SqliteJobStore store(db());
  const std::string a = store.create(spec("a"), "p", "clinic-a", 1).job_id();
  const std::string b = store.create(spec("b"), "p", "clinic-b", 2).job_id();
  const auto listed = store.list(10, "", {}, "clinic-a");
  ASSERT_EQ(listed.size(), 1u);
  EXPECT_EQ(listed[0].job_id(), a);
  EXPECT_TRUE(store.list(10, "", {}, "").empty());
  EXPECT_EQ(store.get(b)->owner, "clinic-b");
}

TEST_F(JobStoreTest, StoreFromBeforeTenantsGetsTheOwnerColumnWithItsJobsSharedByNoTenant) {
  // The schema without the owner column, with one job, as an older server left it.
  const std::string id = "0123456789abcdef";
  {
    sqlite3* old = nullptr;
    ASSERT_EQ(sqlite3_open(db().c_str(), &old), SQLITE_OK);
    v1::Job job;
    job.set_job_id(id);
    job.set_state(v1::Job::SUCCEEDED);
    const std::string sql =
        "CREATE TABLE jobs (seq INTEGER PRIMARY KEY AUTOINCREMENT, id TEXT UNIQUE NOT NULL,"
        " state INTEGER NOT NULL, recording_path TEXT NOT NULL, job BLOB NOT NULL);"
        "INSERT INTO jobs (id, state, recording_path, job) VALUES ('" +
        id + "', 3, 'p', x'" + hex(job.SerializeAsString()) + "');";
    EXPECT_EQ(sqlite3_exec(old, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK);
    sqlite3_close(old);
  }
  {
    SqliteJobStore store(db());  // reopening keeps the column and the job
    EXPECT_EQ(store.get(id)->owner, "");
    EXPECT_EQ(store.list(10, "", {}, "").size(), 1u);
  }
}

}  // namespace
}  // namespace posefuse::server
