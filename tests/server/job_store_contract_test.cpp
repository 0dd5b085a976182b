// The shared-queue contract of JobStore, on SQLite and on PostgreSQL (a private cluster,
// tests/server/postgres_cluster.hpp): claims take the oldest queued job and count attempts,
// leases renew and expire, writes under a lost lease are refused, attempts run out with a clear
// error, cancel, release, events, uploads, results in pages, the heartbeat's probe. Then what only PostgreSQL has:
// claims from two stores at once never take the same job, a newer schema is refused, an unreachable database is
// StoreUnavailable.
#include <atomic>
#include <condition_variable>
#include <fstream>
#include <mutex>
#include <set>
#include <thread>

#include <gtest/gtest.h>

#include "common/error.hpp"
#include "server/job_store_errors.hpp"
#include "server/pg_job_store.hpp"
#include "server/pg_schema.hpp"
#include "server/sqlite_job_store.hpp"
#include "tests/server/postgres_test.hpp"
#include "tests/server/test_support.hpp"

namespace posefuse::server {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

v1::JobSpec spec(const std::string& label) {
  v1::JobSpec s;
  s.set_label(label);
  s.set_recording_uri(label + ".pfchunks");
  return s;
}

JobLease lease_of(const JobRecord& record, const std::string& worker) {
  return {record.job.job_id(), worker, record.attempts};
}

// Events as they arrive (PostgreSQL delivers them on its listener thread).
class EventLog {
 public:
  void add(const JobEvent& event) {
    std::lock_guard lock(mu_);
    events_.push_back(event);
    arrived_.notify_all();
  }
  bool wait_for(JobEvent::Kind kind, const std::string& job_id) {
    std::unique_lock lock(mu_);
    return arrived_.wait_for(lock, 10s, [&] {
      for (const JobEvent& e : events_) {
        if (e.kind == kind && e.job_id == job_id) return true;
      }
      return false;
    });
  }

 private:
  std::mutex mu_;
  std::condition_variable arrived_;
  std::vector<JobEvent> events_;
};

class JobStoreContract : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    if (GetParam() == "postgresql") {
      cluster_ = test::start_postgres();
      if (!cluster_) return;
      conninfo_ = cluster_->conninfo(cluster_->create_database());
    }
    store_ = open();
    store_->set_event_listener([this](const JobEvent& e) { events_.add(e); });
  }
  void TearDown() override {
    if (store_) store_->set_event_listener({});
  }
  std::unique_ptr<JobStore> open() {
    if (GetParam() == "postgresql") return std::make_unique<PgJobStore>(conninfo_);
    return std::make_unique<SqliteJobStore>(dir_ / "jobs.sqlite");
  }

  test::TempDir temp_;
  const fs::path& dir_ = temp_.path();
  std::unique_ptr<test::PostgresCluster> cluster_;
  std::string conninfo_;
  std::unique_ptr<JobStore> store_;
  EventLog events_;
};

TEST_P(JobStoreContract, ClaimTakesTheOldestQueuedJobOnceAndCountsTheAttempt) {
  const std::string a = store_->create(spec("a"), "pa", "clinic", 1).job_id();
  const std::string b = store_->create(spec("b"), "pb", "clinic", 2).job_id();
  const auto first = store_->claim("w1", 10s, 3);
  ASSERT_TRUE(first);
  EXPECT_EQ(first->job.job_id(), a);
  EXPECT_EQ(first->job.state(), v1::Job::RUNNING);
  EXPECT_EQ(first->attempts, 1u);
  EXPECT_EQ(first->recording_path, "pa");
  EXPECT_EQ(first->owner, "clinic");
  EXPECT_EQ(store_->get(a)->job.state(), v1::Job::RUNNING);
  const auto second = store_->claim("w2", 10s, 4);
  ASSERT_TRUE(second);
  EXPECT_EQ(second->job.job_id(), b);
  EXPECT_FALSE(store_->claim("w3", 10s, 5));
  EXPECT_EQ(store_->renew(lease_of(*first, "w1"), 10s), LeaseState::kHeld);
  EXPECT_EQ(store_->renew(lease_of(*first, "w2"), 10s), LeaseState::kLost);
  EXPECT_TRUE(store_->reap(3, 6).empty());  // both leases are current
}

TEST_P(JobStoreContract, ResultsAreReadInPagesInOrder) {
  const std::string id = store_->create(spec("a"), "p", "", 1).job_id();
  const std::string other = store_->create(spec("b"), "p", "", 2).job_id();
  constexpr std::size_t kResults = 150;
  for (std::size_t batch = 0; batch < kResults; batch += 50) {
    std::vector<v1::FitResult> results(50);
    for (std::size_t i = 0; i < results.size(); ++i) {
      results[i].mutable_progress()->set_chunks_processed(batch + i);
    }
    store_->append_results(id, results);
  }
  v1::FitResult foreign;
  foreign.mutable_progress()->set_chunks_processed(9999);
  store_->append_results(other, {foreign});

  std::vector<std::size_t> page_sizes;
  std::uint64_t next = 0;
  while (true) {
    const std::vector<v1::FitResult> page = store_->results(id, next, 64);
    page_sizes.push_back(page.size());
    for (const v1::FitResult& result : page) {
      EXPECT_EQ(result.progress().chunks_processed(), next) << "result " << next;
      ++next;
    }
    if (page.size() < 64) break;
  }
  EXPECT_EQ(next, kResults);
  EXPECT_EQ(page_sizes, (std::vector<std::size_t>{64, 64, 22}));
  EXPECT_TRUE(store_->results(id, kResults, 64).empty());
  EXPECT_EQ(store_->results(id, 10, 3).size(), 3u);
  EXPECT_EQ(store_->results(id, 10, 3)[0].progress().chunks_processed(), 10u);
}

TEST_P(JobStoreContract, ProbeOfAWorkingStoreSucceeds) { EXPECT_NO_THROW(store_->probe()); }

TEST_P(JobStoreContract, AnExpiredLeaseIsReapedAndTheJobQueuedAgainWithoutItsResults) {
  const std::string id = store_->create(spec("a"), "p", "", 1).job_id();
  const auto claimed = store_->claim("w1", 50ms, 2);
  ASSERT_TRUE(claimed);
  const JobLease old_lease = lease_of(*claimed, "w1");
  v1::FitResult partial;
  partial.mutable_progress()->set_chunks_processed(64);
  store_->append_results(old_lease, {partial});
  std::this_thread::sleep_for(150ms);
  const auto reaped = store_->reap(3, 3);
  ASSERT_EQ(reaped.size(), 1u);
  EXPECT_EQ(reaped[0].job_id, id);
  EXPECT_EQ(reaped[0].state, v1::Job::QUEUED);
  EXPECT_TRUE(store_->results(id, 0, 1000).empty());
  EXPECT_TRUE(events_.wait_for(JobEvent::Kind::kQueued, id));

  // Another worker takes it; the first one's writes are refused from now on.
  const auto again = store_->claim("w2", 10s, 4);
  ASSERT_TRUE(again);
  EXPECT_EQ(again->attempts, 2u);
  EXPECT_EQ(store_->renew(old_lease, 10s), LeaseState::kLost);
  EXPECT_THROW(store_->append_results(old_lease, {partial}), LeaseLost);
  v1::Job stale = claimed->job;
  stale.set_state(v1::Job::SUCCEEDED);
  EXPECT_THROW(store_->update_running(old_lease, stale), LeaseLost);
  EXPECT_TRUE(store_->results(id, 0, 1000).empty());
  EXPECT_EQ(store_->get(id)->job.state(), v1::Job::RUNNING);

  // The holder's writes go through; a terminal state ends the lease.
  store_->append_results(lease_of(*again, "w2"), {partial});
  v1::Job done = again->job;
  done.set_state(v1::Job::SUCCEEDED);
  store_->update_running(lease_of(*again, "w2"), done);
  EXPECT_EQ(store_->results(id, 0, 1000).size(), 1u);
  EXPECT_EQ(store_->get(id)->job.state(), v1::Job::SUCCEEDED);
  EXPECT_EQ(store_->renew(lease_of(*again, "w2"), 10s), LeaseState::kLost);
  EXPECT_TRUE(events_.wait_for(JobEvent::Kind::kChanged, id));
}

TEST_P(JobStoreContract, AJobWhoseLeaseExpiresMaxAttemptsTimesFailsWithAClearError) {
  const std::string id = store_->create(spec("a"), "p", "", 1).job_id();
  for (int attempt = 1; attempt <= 2; ++attempt) {
    ASSERT_TRUE(store_->claim("w", 20ms, 2));
    std::this_thread::sleep_for(60ms);
    const auto reaped = store_->reap(2, 3);
    ASSERT_EQ(reaped.size(), 1u);
    EXPECT_EQ(reaped[0].state, attempt < 2 ? v1::Job::QUEUED : v1::Job::FAILED);
  }
  const v1::Job failed = store_->get(id)->job;
  EXPECT_EQ(failed.state(), v1::Job::FAILED);
  EXPECT_EQ(failed.error_code(), static_cast<int>(grpc::StatusCode::ABORTED));
  EXPECT_EQ(failed.error_message().rfind("job: its worker's lease expired 2 times", 0), 0u) << failed.error_message();
  EXPECT_FALSE(store_->claim("w", 20ms, 4));
}

TEST_P(JobStoreContract, CancelStopsAQueuedJobAtOnceAndAsksARunningOnesWorker) {
  const std::string queued = store_->create(spec("q"), "p", "clinic", 1).job_id();
  const std::string running = store_->create(spec("r"), "p", "clinic", 2).job_id();
  // Another tenant cannot cancel, nor learn that the job exists.
  EXPECT_FALSE(store_->cancel(queued, "other", 3));
  EXPECT_FALSE(store_->cancel("no-such-job", "clinic", 3));

  const auto claimed = store_->claim("w", 10s, 3);  // takes `queued`, the older one
  ASSERT_TRUE(claimed);
  const auto second = store_->claim("w", 10s, 3);
  ASSERT_TRUE(second);
  ASSERT_EQ(second->job.job_id(), running);
  // Release `queued` back to the queue (a server stopping): QUEUED, attempt not counted.
  store_->release(lease_of(*claimed, "w"), 4);
  EXPECT_EQ(store_->get(queued)->job.state(), v1::Job::QUEUED);
  EXPECT_EQ(store_->get(queued)->attempts, 0u);

  EXPECT_EQ(store_->cancel(queued, "clinic", 5)->job.state(), v1::Job::CANCELLED);
  EXPECT_EQ(store_->get(queued)->job.state(), v1::Job::CANCELLED);
  EXPECT_EQ(store_->cancel(running, "clinic", 5)->job.state(), v1::Job::RUNNING);
  EXPECT_TRUE(events_.wait_for(JobEvent::Kind::kCancelRequested, running));
  EXPECT_EQ(store_->renew(lease_of(*second, "w"), 10s), LeaseState::kCancelRequested);
}

TEST_P(JobStoreContract, ListsATenantsJobsNewestFirstInPages) {
  std::vector<std::string> ids;
  for (int i = 0; i < 5; ++i) ids.push_back(store_->create(spec("j"), "p", "a", i).job_id());
  store_->create(spec("other"), "p", "b", 9);
  const auto page = store_->list(2, "", {}, "a");
  ASSERT_EQ(page.size(), 2u);
  EXPECT_EQ(page[0].job_id(), ids[4]);
  const auto next = store_->list(10, page.back().job_id(), {}, "a");
  ASSERT_EQ(next.size(), 3u);
  EXPECT_EQ(next[0].job_id(), ids[2]);
  ASSERT_TRUE(store_->claim("w", 10s, 10));
  const auto running = store_->list(10, "", {v1::Job::RUNNING}, "a");
  ASSERT_EQ(running.size(), 1u);
  EXPECT_EQ(running[0].job_id(), ids[0]);
  EXPECT_EQ(store_->list(10, "", {}, "b").size(), 1u);
}

TEST_P(JobStoreContract, AnUploadIsKeptFetchedAndDropped) {
  // Larger than one stored row (1 MiB), with every byte value.
  std::string bytes;
  for (std::size_t i = 0; i < (3u << 20) / 2; ++i) bytes += static_cast<char>(i * 7 % 256);
  const fs::path spooled = dir_ / "spooled.pfchunks";
  std::ofstream(spooled, std::ios::binary) << bytes;
  fs::create_directories(dir_ / "scratch");
  const std::string kept = store_->keep_upload(spooled);
  const fs::path local = store_->local_recording(kept, dir_ / "scratch");
  std::ifstream in(local, std::ios::binary);
  const std::string read((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(read.size(), bytes.size());
  EXPECT_TRUE(read == bytes);
  store_->drop_upload(kept, dir_ / "scratch");
  EXPECT_FALSE(fs::exists(local));
  if (GetParam() == "postgresql") {
    EXPECT_FALSE(fs::exists(spooled));  // the bytes moved into the database
    try {
      store_->local_recording(kept, dir_ / "scratch");
      FAIL() << "no error";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kNotFound);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Stores, JobStoreContract, ::testing::Values("sqlite", "postgresql"),
                         [](const auto& info) { return info.param; });

class PgJobStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    cluster_ = test::start_postgres();
    if (cluster_) conninfo_ = cluster_->conninfo(cluster_->create_database());
  }
  std::unique_ptr<test::PostgresCluster> cluster_;
  std::string conninfo_;
};

TEST_F(PgJobStoreTest, ClaimsFromTwoStoresAtOnceNeverTakeTheSameJob) {
  PgJobStore submitter(conninfo_);
  constexpr int kJobs = 60;
  for (int i = 0; i < kJobs; ++i) submitter.create(spec("j"), "p", "", i);
  PgJobStore a(conninfo_), b(conninfo_);
  std::mutex mu;
  std::multiset<std::string> claimed;
  auto worker = [&](PgJobStore& store, const std::string& name) {
    while (const auto record = store.claim(name, 10s, 1)) {
      std::lock_guard lock(mu);
      claimed.insert(record->job.job_id());
    }
  };
  std::vector<std::thread> threads;
  for (int i = 0; i < 3; ++i) {
    threads.emplace_back(worker, std::ref(a), "a" + std::to_string(i));
    threads.emplace_back(worker, std::ref(b), "b" + std::to_string(i));
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(claimed.size(), static_cast<std::size_t>(kJobs));
  EXPECT_EQ(std::set<std::string>(claimed.begin(), claimed.end()).size(), static_cast<std::size_t>(kJobs));
}

TEST_F(PgJobStoreTest, ADatabaseWithANewerSchemaIsRefusedWithBothVersions) {
  { PgJobStore first(conninfo_); }  // migrates
  {
    PgConnection admin(conninfo_);
    admin.exec("UPDATE posefuse_schema SET version = $1", {pg_int(pg_schema_version() + 5)});
  }
  try {
    PgJobStore refused(conninfo_);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kFailedPrecondition);
    const std::string expected = "the database's posefuse schema is version " +
                                 std::to_string(pg_schema_version() + 5) + ", newer than this posefuse-server knows (" +
                                 std::to_string(pg_schema_version()) + ")";
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    // Never passes by waiting: a server does not start on it (DeferredJobStore).
    EXPECT_NE(dynamic_cast<const StoreMisconfigured*>(&e), nullptr);
  }
}

TEST_F(PgJobStoreTest, StartingTogetherMigratesOnceAndReopeningKeepsTheJobs) {
  std::vector<std::thread> threads;
  std::atomic<int> failures{0};
  for (int i = 0; i < 4; ++i) {
    threads.emplace_back([&] {
      try {
        PgJobStore store(conninfo_);
      } catch (const std::exception&) {
        ++failures;
      }
    });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(failures, 0);
  std::string id;
  { id = PgJobStore(conninfo_).create(spec("kept"), "p", "", 1).job_id(); }
  PgJobStore reopened(conninfo_);
  ASSERT_TRUE(reopened.get(id));
  EXPECT_EQ(reopened.get(id)->job.label(), "kept");
}

// The value libpq uses for `keyword` on an open connection.
std::string option_in_use(PgConnection& connection, const std::string& keyword) {
  PQconninfoOption* options = PQconninfo(connection.raw());
  std::string value = "(absent)";
  for (PQconninfoOption* o = options; o && o->keyword; ++o) {
    if (keyword == o->keyword) value = o->val ? o->val : "(unset)";
  }
  PQconninfoFree(options);
  return value;
}

TEST_F(PgJobStoreTest, ConnectionsGiveUpAndNoticeADeadPeerUnlessTheConninfoSaysOtherwise) {
  PgConnection defaults(conninfo_);
  EXPECT_EQ(option_in_use(defaults, "connect_timeout"), kPgConnectTimeoutS);
  EXPECT_EQ(option_in_use(defaults, "keepalives"), "1");
  EXPECT_EQ(option_in_use(defaults, "keepalives_idle"), kPgKeepalivesIdleS);
  EXPECT_EQ(option_in_use(defaults, "keepalives_interval"), kPgKeepalivesIntervalS);
  EXPECT_EQ(option_in_use(defaults, "keepalives_count"), kPgKeepalivesCount);
  // The conninfo's own settings win, and the rest of it (database, socket) still applies.
  PgConnection own(conninfo_ + " keepalives_idle=7 connect_timeout=3");
  EXPECT_EQ(option_in_use(own, "keepalives_idle"), "7");
  EXPECT_EQ(option_in_use(own, "connect_timeout"), "3");
  EXPECT_EQ(option_in_use(own, "keepalives_count"), kPgKeepalivesCount);
  EXPECT_EQ(option_in_use(own, "dbname"), option_in_use(defaults, "dbname"));
  EXPECT_EQ(own.exec("SELECT 1").get() != nullptr, true);
}

TEST_F(PgJobStoreTest, AnUnreachableDatabaseIsStoreUnavailableAndABadConninfoNamesTheFlag) {
  try {
    PgJobStore store("host=/nonexistent/socket/dir dbname=x");
    FAIL() << "no error";
  } catch (const StoreUnavailable& e) {
    EXPECT_NE(std::string(e.what()).find("cannot connect to the PostgreSQL job store"), std::string::npos) << e.what();
  }
  try {
    PgJobStore store("host=/tmp nonsense_key=1");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_EQ(e.field(), "--job-store");
  }
}

}  // namespace
}  // namespace posefuse::server
