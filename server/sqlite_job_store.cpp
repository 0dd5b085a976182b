#include "server/sqlite_job_store.hpp"

#include <sqlite3.h>

#include "common/error.hpp"
#include "server/random_id.hpp"

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
    check(sqlite3_bind_text(stmt_, index, text.data(), static_cast<int>(text.size()),
                            SQLITE_TRANSIENT));
    return *this;
  }
  Statement& bind_blob(int index, const std::string& bytes) {
    check(sqlite3_bind_blob(stmt_, index, bytes.data(), static_cast<int>(bytes.size()),
                            SQLITE_TRANSIENT));
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
    return p ? std::string(p, static_cast<std::size_t>(sqlite3_column_bytes(stmt_, column)))
             : std::string();
  }
  std::string blob(int column) const {
    const auto* p = static_cast<const char*>(sqlite3_column_blob(stmt_, column));
    return p ? std::string(p, static_cast<std::size_t>(sqlite3_column_bytes(stmt_, column)))
             : std::string();
  }

 private:
  void check(int rc) {
    if (rc != SQLITE_OK) fail("bind");
  }
  [[noreturn]] void fail(const char* what) {
    throw Error(store_error_code(sqlite3_errcode(db_)), "job_store",
                std::string(what) + ": " + sqlite3_errmsg(db_));
  }
  sqlite3* db_;
  sqlite3_stmt* stmt_ = nullptr;
};

v1::Job parse_job(const std::string& bytes) {
  v1::Job job;
  if (!job.ParseFromString(bytes)) {
    throw Error(ErrorCode::kDataLoss, "job_store.jobs.job", "stored job does not parse");
  }
  return job;
}

}  // namespace

SqliteJobStore::SqliteJobStore(const std::filesystem::path& path) : path_(path) {
  if (sqlite3_open_v2(path.c_str(), &db_,
                      SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX,
                      nullptr) != SQLITE_OK) {
    const std::string message = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw Error(ErrorCode::kFailedPrecondition, path.string(), "cannot open the job store: " + message);
  }
  sqlite3_busy_timeout(db_, 5000);
  try {
    exec("PRAGMA journal_mode=WAL");
    exec("CREATE TABLE IF NOT EXISTS jobs ("
         " seq INTEGER PRIMARY KEY AUTOINCREMENT, id TEXT UNIQUE NOT NULL,"
         " state INTEGER NOT NULL, recording_path TEXT NOT NULL, job BLOB NOT NULL)");
    // The owning tenant; a store made before tenants gets the column, its jobs owned by "".
    if (!has_column("jobs", "owner")) exec("ALTER TABLE jobs ADD COLUMN owner TEXT NOT NULL DEFAULT ''");
    exec("CREATE TABLE IF NOT EXISTS results ("
         " job_id TEXT NOT NULL, seq INTEGER NOT NULL, result BLOB NOT NULL,"
         " PRIMARY KEY (job_id, seq))");
  } catch (const Error& error) {
    sqlite3_close(db_);
    throw Error(ErrorCode::kFailedPrecondition, path.string(), error.what());
  }
}

SqliteJobStore::~SqliteJobStore() { sqlite3_close(db_); }

void SqliteJobStore::exec(const char* sql) {
  char* message = nullptr;
  if (const int rc = sqlite3_exec(db_, sql, nullptr, nullptr, &message); rc != SQLITE_OK) {
    const std::string text = message ? message : "unknown error";
    sqlite3_free(message);
    throw Error(store_error_code(rc), "job_store", text);
  }
}

bool SqliteJobStore::has_column(const char* table, const char* column) {
  Statement select(db_, std::string("SELECT COUNT(*) FROM pragma_table_info('") + table +
                            "') WHERE name = ?");
  select.bind(1, std::string(column));
  return select.step() && select.int64(0) > 0;
}

v1::Job SqliteJobStore::create(const v1::JobSpec& spec, const std::string& recording_path,
                               const std::string& owner, std::int64_t now_unix_us) {
  v1::Job job;
  job.set_job_id(random_hex_id());
  job.set_state(v1::Job::QUEUED);
  job.set_create_time_unix_us(now_unix_us);
  job.set_update_time_unix_us(now_unix_us);
  job.set_label(spec.label());
  if (spec.has_recording_uri()) job.set_recording_uri(spec.recording_uri());
  std::lock_guard lock(mu_);
  Statement insert(db_,
                   "INSERT INTO jobs (id, state, recording_path, job, owner) VALUES (?, ?, ?, ?, ?)");
  insert.bind(1, job.job_id()).bind(2, std::int64_t{job.state()}).bind(3, recording_path);
  insert.bind_blob(4, job.SerializeAsString()).bind(5, owner);
  insert.step();
  return job;
}

std::optional<JobRecord> SqliteJobStore::get(const std::string& job_id) {
  std::lock_guard lock(mu_);
  Statement select(db_, "SELECT job, recording_path, owner FROM jobs WHERE id = ?");
  select.bind(1, job_id);
  if (!select.step()) return std::nullopt;
  return JobRecord{parse_job(select.blob(0)), select.text(1), select.text(2)};
}

std::vector<v1::Job> SqliteJobStore::list(std::size_t limit, const std::string& after_job_id,
                                          const std::vector<v1::Job::State>& states,
                                          const std::string& owner) {
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
  std::lock_guard lock(mu_);
  Statement update(db_, "UPDATE jobs SET state = ?, job = ? WHERE id = ?");
  update.bind(1, std::int64_t{job.state()}).bind_blob(2, job.SerializeAsString());
  update.bind(3, job.job_id());
  update.step();
  if (sqlite3_changes(db_) == 0) {
    throw Error(ErrorCode::kNotFound, "job_id", "no job '" + job.job_id() + "'");
  }
}

void SqliteJobStore::append_results(const std::string& job_id,
                                    const std::vector<v1::FitResult>& results) {
  std::lock_guard lock(mu_);
  exec("BEGIN IMMEDIATE");
  try {
    Statement next(db_, "SELECT COALESCE(MAX(seq) + 1, 0) FROM results WHERE job_id = ?");
    next.bind(1, job_id);
    next.step();
    std::int64_t seq = next.int64(0);
    for (const v1::FitResult& result : results) {
      Statement row(db_, "INSERT INTO results (job_id, seq, result) VALUES (?, ?, ?)");
      row.bind(1, job_id).bind(2, seq++).bind_blob(3, result.SerializeAsString());
      row.step();
    }
    exec("COMMIT");
  } catch (...) {
    // Not exec(): SQLite may have rolled back already (a full disk does that), and the error
    // to report is the one that got us here.
    sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
}

std::vector<v1::FitResult> SqliteJobStore::results(const std::string& job_id) {
  std::lock_guard lock(mu_);
  Statement select(db_, "SELECT result FROM results WHERE job_id = ? ORDER BY seq");
  select.bind(1, job_id);
  std::vector<v1::FitResult> results;
  while (select.step()) {
    if (!results.emplace_back().ParseFromString(select.blob(0))) {
      throw Error(ErrorCode::kDataLoss, "job_store.results", "stored result does not parse");
    }
  }
  return results;
}

void SqliteJobStore::clear_results(const std::string& job_id) {
  std::lock_guard lock(mu_);
  Statement remove(db_, "DELETE FROM results WHERE job_id = ?");
  remove.bind(1, job_id);
  remove.step();
}

std::vector<JobRecord> SqliteJobStore::unfinished() {
  std::lock_guard lock(mu_);
  Statement select(db_, "SELECT job, recording_path, owner FROM jobs WHERE state IN (?, ?) ORDER BY seq");
  select.bind(1, std::int64_t{v1::Job::QUEUED}).bind(2, std::int64_t{v1::Job::RUNNING});
  std::vector<JobRecord> records;
  while (select.step()) records.push_back({parse_job(select.blob(0)), select.text(1), select.text(2)});
  return records;
}

}  // namespace posefuse::server
