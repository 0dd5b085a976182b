#include "server/sqlite_job_store.hpp"

#include <fcntl.h>
#include <sqlite3.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>

#include "common/error.hpp"
#include "server/job_store_errors.hpp"
#include "server/job_transitions.hpp"

namespace posefuse::server {

namespace {

// A full disk (or a full database) is a resource running out; anything else is ours to fix.
ErrorCode store_error_code(int rc) {
  return (rc & 0xff) == SQLITE_FULL ? ErrorCode::kResourceExhausted : ErrorCode::kInternal;
}

// One prepared statement; finalized on destruction. Errors throw kInternal (kResourceExhausted
// for a full disk) with SQLite's text.
class Statement {
 public:
  Statement(sqlite3* db, const std::string& sql) : db_(db) {
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &stmt_, nullptr) != SQLITE_OK) fail("prepare");
  }
  ~Statement() { sqlite3_finalize(stmt_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  Statement& bind(int index, const std::string& text) {
    check(sqlite3_bind_text(stmt_, index, text.data(), static_cast<int>(text.size()), SQLITE_TRANSIENT));
    return *this;
  }
  Statement& bind_blob(int index, const std::string& bytes) {
    check(sqlite3_bind_blob(stmt_, index, bytes.data(), static_cast<int>(bytes.size()), SQLITE_TRANSIENT));
    return *this;
  }
  Statement& bind(int index, std::int64_t value) {
    check(sqlite3_bind_int64(stmt_, index, value));
    return *this;
  }
  // True while there is a row.
  bool step() {
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc != SQLITE_DONE) fail("step");
    return false;
  }
  std::int64_t int64(int column) const { return sqlite3_column_int64(stmt_, column); }
  std::string text(int column) const {
    const auto* p = reinterpret_cast<const char*>(sqlite3_column_text(stmt_, column));
    return p ? std::string(p, static_cast<std::size_t>(sqlite3_column_bytes(stmt_, column))) : std::string();
  }
  std::string blob(int column) const {
    const auto* p = static_cast<const char*>(sqlite3_column_blob(stmt_, column));
    return p ? std::string(p, static_cast<std::size_t>(sqlite3_column_bytes(stmt_, column))) : std::string();
  }

 private:
  void check(int rc) {
    if (rc != SQLITE_OK) fail("bind");
  }
  [[noreturn]] void fail(const char* what) {
    throw Error(store_error_code(sqlite3_errcode(db_)), "job_store", std::string(what) + ": " + sqlite3_errmsg(db_));
  }
  sqlite3* db_;
  sqlite3_stmt* stmt_ = nullptr;
};

std::int64_t system_now_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

v1::Job parse_job(const std::string& bytes) { return parse_stored_job(bytes, "job_store.jobs.job"); }

constexpr const char* kRecordColumns = "job, recording_path, owner, attempts";

JobRecord read_record(const Statement& row) {
  return {parse_job(row.blob(0)), row.text(1), row.text(2), static_cast<std::uint32_t>(row.int64(3))};
}

}  // namespace

SqliteJobStore::SqliteJobStore(const std::filesystem::path& path) : path_(path) {
  // The store treats every lease as over when it opens (one process owns it): a second process
  // on the same file would take over the first one's running jobs, so it is refused.
  std::filesystem::path lock_path = path;
  lock_path += ".lock";
  lock_fd_ = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0600);
  if (lock_fd_ < 0) {
    throw Error(ErrorCode::kFailedPrecondition, path.string(),
                std::string("cannot open the job store's lock file: ") + std::strerror(errno));
  }
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    ::close(lock_fd_);
    throw StoreMisconfigured(path.string(),
                             "another posefuse-server process uses this job store (SQLite serves one process; "
                             "replicas share a PostgreSQL one: --job-store)");
  }
  if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX,
                      nullptr) != SQLITE_OK) {
    const std::string message = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    ::close(lock_fd_);
    throw Error(ErrorCode::kFailedPrecondition, path.string(), "cannot open the job store: " + message);
  }
  sqlite3_busy_timeout(db_, 5000);
  try {
    exec("PRAGMA journal_mode=WAL");
    exec(
        "CREATE TABLE IF NOT EXISTS jobs ("
        " seq INTEGER PRIMARY KEY AUTOINCREMENT, id TEXT UNIQUE NOT NULL,"
        " state INTEGER NOT NULL, recording_path TEXT NOT NULL, job BLOB NOT NULL)");
    // The owning tenant; a store made before tenants gets the column, its jobs owned by "".
    if (!has_column("jobs", "owner")) exec("ALTER TABLE jobs ADD COLUMN owner TEXT NOT NULL DEFAULT ''");
    // The lease columns of the shared queue (job_store.hpp); a job left RUNNING by an older
    // server has an expired lease, so the first reap() takes it up again.
    if (!has_column("jobs", "attempts")) {
      exec("ALTER TABLE jobs ADD COLUMN attempts INTEGER NOT NULL DEFAULT 0");
      exec("ALTER TABLE jobs ADD COLUMN lease_owner TEXT NOT NULL DEFAULT ''");
      exec("ALTER TABLE jobs ADD COLUMN lease_expires_us INTEGER NOT NULL DEFAULT 0");
      exec("ALTER TABLE jobs ADD COLUMN cancel_requested INTEGER NOT NULL DEFAULT 0");
    }
    // One process owns this file: a job RUNNING at open was left by a process that stopped,
    // so its lease is over now rather than after its expiry time.
    exec("UPDATE jobs SET lease_expires_us = 0 WHERE state = 2");
    exec(
        "CREATE TABLE IF NOT EXISTS results ("
        " job_id TEXT NOT NULL, seq INTEGER NOT NULL, result BLOB NOT NULL,"
        " PRIMARY KEY (job_id, seq))");
    // One row that probe() rewrites on every heartbeat.
    exec("CREATE TABLE IF NOT EXISTS heartbeat (id INTEGER PRIMARY KEY CHECK (id = 1), at_us INTEGER NOT NULL)");
  } catch (const Error& error) {
    sqlite3_close(db_);
    ::close(lock_fd_);
    throw Error(ErrorCode::kFailedPrecondition, path.string(), error.what());
  }
}

SqliteJobStore::~SqliteJobStore() {
  sqlite3_close(db_);
  ::close(lock_fd_);  // releases the lock
}

void SqliteJobStore::exec(const char* sql) {
  char* message = nullptr;
  if (const int rc = sqlite3_exec(db_, sql, nullptr, nullptr, &message); rc != SQLITE_OK) {
    const std::string text = message ? message : "unknown error";
    sqlite3_free(message);
    throw Error(store_error_code(rc), "job_store", text);
  }
}

template <class Body>
void SqliteJobStore::in_transaction(Body&& body) {
  exec("BEGIN IMMEDIATE");
  try {
    body();
    exec("COMMIT");
  } catch (...) {
    // Not exec(): SQLite may have rolled back already (a full disk does that), and the error
    // to report is the one that got us here.
    sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
}

bool SqliteJobStore::has_column(const char* table, const char* column) {
  Statement select(db_, std::string("SELECT COUNT(*) FROM pragma_table_info('") + table + "') WHERE name = ?");
  select.bind(1, std::string(column));
  return select.step() && select.int64(0) > 0;
}

v1::Job SqliteJobStore::create(const v1::JobSpec& spec, const std::string& recording_path, const std::string& owner,
                               std::int64_t now_unix_us) {
  const v1::Job job = new_job(spec, now_unix_us);
  {
    std::lock_guard lock(mu_);
    Statement insert(db_, "INSERT INTO jobs (id, state, recording_path, job, owner) VALUES (?, ?, ?, ?, ?)");
    insert.bind(1, job.job_id()).bind(2, std::int64_t{job.state()}).bind(3, recording_path);
    insert.bind_blob(4, job.SerializeAsString()).bind(5, owner);
    insert.step();
  }
  notify({JobEvent::Kind::kQueued, job.job_id()});
  return job;
}

std::optional<JobRecord> SqliteJobStore::get(const std::string& job_id) {
  std::lock_guard lock(mu_);
  Statement select(db_, std::string("SELECT ") + kRecordColumns + " FROM jobs WHERE id = ?");
  select.bind(1, job_id);
  if (!select.step()) return std::nullopt;
  return read_record(select);
}

std::vector<v1::Job> SqliteJobStore::list(std::size_t limit, const std::string& after_job_id,
                                          const std::vector<v1::Job::State>& states, const std::string& owner) {
  std::string sql = "SELECT job FROM jobs WHERE owner = ?";
  if (!after_job_id.empty()) sql += " AND seq < (SELECT seq FROM jobs WHERE id = ?)";
  if (!states.empty()) {
    sql += " AND state IN (";
    for (std::size_t i = 0; i < states.size(); ++i) sql += i ? ", ?" : "?";
    sql += ")";
  }
  sql += " ORDER BY seq DESC LIMIT ?";
  std::lock_guard lock(mu_);
  Statement select(db_, sql);
  int index = 1;
  select.bind(index++, owner);
  if (!after_job_id.empty()) select.bind(index++, after_job_id);
  for (const v1::Job::State state : states) select.bind(index++, std::int64_t{state});
  select.bind(index, static_cast<std::int64_t>(limit));
  std::vector<v1::Job> jobs;
  while (select.step()) jobs.push_back(parse_job(select.blob(0)));
  return jobs;
}

void SqliteJobStore::update(const v1::Job& job) {
  {
    std::lock_guard lock(mu_);
    write_job_locked(job);
    if (sqlite3_changes(db_) == 0) {
      throw Error(ErrorCode::kNotFound, "job_id", "no job '" + job.job_id() + "'");
    }
  }
  notify({JobEvent::Kind::kChanged, job.job_id()});
}

void SqliteJobStore::append_results(const std::string& job_id, const std::vector<v1::FitResult>& results) {
  std::lock_guard lock(mu_);
  in_transaction([&] { append_results_locked(job_id, results); });
}

void SqliteJobStore::append_results_locked(const std::string& job_id, const std::vector<v1::FitResult>& results) {
  {
    Statement next(db_, "SELECT COALESCE(MAX(seq) + 1, 0) FROM results WHERE job_id = ?");
    next.bind(1, job_id);
    next.step();
    std::int64_t seq = next.int64(0);
    for (const v1::FitResult& result : results) {
      Statement row(db_, "INSERT INTO results (job_id, seq, result) VALUES (?, ?, ?)");
      row.bind(1, job_id).bind(2, seq++).bind_blob(3, result.SerializeAsString());
      row.step();
    }
  }
}

std::vector<v1::FitResult> SqliteJobStore::results(const std::string& job_id, std::uint64_t first, std::size_t limit) {
  std::lock_guard lock(mu_);
  Statement select(db_, "SELECT result FROM results WHERE job_id = ? AND seq >= ? ORDER BY seq LIMIT ?");
  select.bind(1, job_id).bind(2, static_cast<std::int64_t>(first)).bind(3, static_cast<std::int64_t>(limit));
  std::vector<v1::FitResult> results;
  while (select.step()) {
    if (!results.emplace_back().ParseFromString(select.blob(0))) {
      throw Error(ErrorCode::kDataLoss, "job_store.results", "stored result does not parse");
    }
  }
  return results;
}

void SqliteJobStore::clear_results_locked(const std::string& job_id) {
  Statement remove(db_, "DELETE FROM results WHERE job_id = ?");
  remove.bind(1, job_id);
  remove.step();
}

void SqliteJobStore::write_job_locked(const v1::Job& job) {
  Statement update(db_, "UPDATE jobs SET state = ?, job = ? WHERE id = ?");
  update.bind(1, std::int64_t{job.state()}).bind_blob(2, job.SerializeAsString());
  update.bind(3, job.job_id());
  update.step();
}

bool SqliteJobStore::holds_locked(const JobLease& lease) {
  Statement select(db_,
                   "SELECT COUNT(*) FROM jobs WHERE id = ? AND lease_owner = ? AND attempts = ?"
                   " AND state = ?");
  select.bind(1, lease.job_id).bind(2, lease.worker).bind(3, std::int64_t{lease.attempt});
  select.bind(4, std::int64_t{v1::Job::RUNNING});
  return select.step() && select.int64(0) > 0;
}

std::optional<JobRecord> SqliteJobStore::cancel(const std::string& job_id, const std::string& owner,
                                                std::int64_t now_unix_us) {
  std::optional<JobRecord> record;
  std::optional<JobEvent> event;
  {
    std::lock_guard lock(mu_);
    in_transaction([&] {
      Statement select(db_, std::string("SELECT ") + kRecordColumns + " FROM jobs WHERE id = ?");
      select.bind(1, job_id);
      if (!select.step()) return;
      record = read_record(select);
      if (record->owner != owner) {
        record.reset();
        return;
      }
      if (record->job.state() == v1::Job::QUEUED) {
        mark_cancelled(record->job, now_unix_us);
        write_job_locked(record->job);
        event = JobEvent{JobEvent::Kind::kChanged, job_id};
      } else if (record->job.state() == v1::Job::RUNNING) {
        Statement mark(db_, "UPDATE jobs SET cancel_requested = 1 WHERE id = ?");
        mark.bind(1, job_id);
        mark.step();
        event = JobEvent{JobEvent::Kind::kCancelRequested, job_id};
      }
    });
  }
  if (event) notify(*event);
  return record;
}

std::optional<JobRecord> SqliteJobStore::claim(const std::string& worker, std::chrono::milliseconds lease,
                                               std::int64_t now_unix_us) {
  std::optional<JobRecord> record;
  {
    std::lock_guard lock(mu_);
    in_transaction([&] {
      Statement select(db_,
                       std::string("SELECT ") + kRecordColumns + " FROM jobs WHERE state = ? ORDER BY seq LIMIT 1");
      select.bind(1, std::int64_t{v1::Job::QUEUED});
      if (!select.step()) return;
      record = read_record(select);
      record->attempts += 1;
      mark_claimed(record->job, now_unix_us);
      clear_results_locked(record->job.job_id());
      Statement update(db_,
                       "UPDATE jobs SET state = ?, job = ?, attempts = ?, lease_owner = ?,"
                       " lease_expires_us = ?, cancel_requested = 0 WHERE id = ?");
      update.bind(1, std::int64_t{v1::Job::RUNNING}).bind_blob(2, record->job.SerializeAsString());
      update.bind(3, std::int64_t{record->attempts}).bind(4, worker);
      update.bind(5, system_now_us() + std::chrono::microseconds(lease).count());
      update.bind(6, record->job.job_id());
      update.step();
    });
  }
  if (record) notify({JobEvent::Kind::kChanged, record->job.job_id()});
  return record;
}

LeaseState SqliteJobStore::renew(const JobLease& lease, std::chrono::milliseconds duration) {
  std::lock_guard lock(mu_);
  Statement update(db_,
                   "UPDATE jobs SET lease_expires_us = ? WHERE id = ? AND lease_owner = ?"
                   " AND attempts = ? AND state = ? RETURNING cancel_requested");
  update.bind(1, system_now_us() + std::chrono::microseconds(duration).count());
  update.bind(2, lease.job_id).bind(3, lease.worker).bind(4, std::int64_t{lease.attempt});
  update.bind(5, std::int64_t{v1::Job::RUNNING});
  if (!update.step()) return LeaseState::kLost;
  const bool cancel = update.int64(0) != 0;
  while (update.step()) {
  }
  return cancel ? LeaseState::kCancelRequested : LeaseState::kHeld;
}

void SqliteJobStore::update_running(const JobLease& lease, const v1::Job& job) {
  {
    std::lock_guard lock(mu_);
    in_transaction([&] {
      if (!holds_locked(lease)) throw LeaseLost(lease.job_id);
      write_job_locked(job);
      if (is_terminal(job.state())) {
        Statement end(db_, "UPDATE jobs SET lease_owner = '' WHERE id = ?");
        end.bind(1, job.job_id());
        end.step();
      }
    });
  }
  notify({JobEvent::Kind::kChanged, job.job_id()});
}

void SqliteJobStore::append_results(const JobLease& lease, const std::vector<v1::FitResult>& results) {
  std::lock_guard lock(mu_);
  in_transaction([&] {
    if (!holds_locked(lease)) throw LeaseLost(lease.job_id);
    append_results_locked(lease.job_id, results);
  });
}

void SqliteJobStore::release(const JobLease& lease, std::int64_t now_unix_us) {
  bool released = false;
  {
    std::lock_guard lock(mu_);
    in_transaction([&] {
      if (!holds_locked(lease)) return;
      Statement select(db_, "SELECT job FROM jobs WHERE id = ?");
      select.bind(1, lease.job_id);
      if (!select.step()) return;
      v1::Job job = parse_job(select.blob(0));
      mark_queued_again(job, now_unix_us);
      write_job_locked(job);
      Statement update(db_, "UPDATE jobs SET attempts = attempts - 1, lease_owner = '' WHERE id = ?");
      update.bind(1, lease.job_id);
      update.step();
      clear_results_locked(lease.job_id);
      released = true;
    });
  }
  if (released) notify({JobEvent::Kind::kQueued, lease.job_id});
}

std::vector<ReapedJob> SqliteJobStore::reap(std::uint32_t max_attempts, std::int64_t now_unix_us) {
  std::vector<ReapedJob> reaped;
  {
    std::lock_guard lock(mu_);
    in_transaction([&] {
      std::vector<std::pair<JobRecord, bool>> expired;
      {
        Statement select(db_, std::string("SELECT ") + kRecordColumns +
                                  ", cancel_requested FROM jobs WHERE state = ? AND"
                                  " lease_expires_us < ? ORDER BY seq");
        select.bind(1, std::int64_t{v1::Job::RUNNING}).bind(2, system_now_us());
        while (select.step()) expired.emplace_back(read_record(select), select.int64(4) != 0);
      }
      for (auto& [record, cancel_requested] : expired) {
        const v1::Job::State state =
            mark_lease_expired(record.job, record.attempts, max_attempts, cancel_requested, now_unix_us);
        write_job_locked(record.job);
        Statement end(db_, "UPDATE jobs SET lease_owner = '' WHERE id = ?");
        end.bind(1, record.job.job_id());
        end.step();
        if (state == v1::Job::QUEUED) clear_results_locked(record.job.job_id());
        reaped.push_back({record.job.job_id(), state});
      }
    });
  }
  for (const ReapedJob& job : reaped) {
    notify({job.state == v1::Job::QUEUED ? JobEvent::Kind::kQueued : JobEvent::Kind::kChanged, job.job_id});
  }
  return reaped;
}

void SqliteJobStore::probe() {
  std::lock_guard lock(mu_);
  Statement write(
      db_, "INSERT INTO heartbeat (id, at_us) VALUES (1, ?) ON CONFLICT (id) DO UPDATE SET at_us = excluded.at_us");
  write.bind(1, system_now_us());
  write.step();
}

void SqliteJobStore::set_event_listener(std::function<void(const JobEvent&)> listener) {
  std::lock_guard lock(listener_mu_);
  listener_ = std::move(listener);
}

void SqliteJobStore::notify(const JobEvent& event) {
  std::lock_guard lock(listener_mu_);
  if (listener_) listener_(event);
}

std::string SqliteJobStore::keep_upload(const std::filesystem::path& spooled) { return spooled.string(); }

std::filesystem::path SqliteJobStore::local_recording(const std::string& recording_path, const std::filesystem::path&) {
  return recording_path;
}

void SqliteJobStore::drop_upload(const std::string& recording_path, const std::filesystem::path&) {
  std::error_code ignored;
  std::filesystem::remove(recording_path, ignored);
}

}  // namespace posefuse::server
