#include "server/pg_connection.hpp"

#include <cstring>

#include "common/error.hpp"
#include "server/job_store_errors.hpp"

namespace posefuse::server {

namespace {

std::string trimmed(const char* text) {
  std::string s = text ? text : "";
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  return s;
}

// SQLSTATE classes that mean the server is away rather than the statement being wrong:
// 08 connection exception, 57P0x the server shutting down or starting.
bool server_away(const std::string& sqlstate) { return sqlstate.rfind("08", 0) == 0 || sqlstate.rfind("57P0", 0) == 0; }

}  // namespace

PgParam pg_text(std::string value) { return {std::move(value), false}; }
PgParam pg_int(std::int64_t value) { return {std::to_string(value), false}; }
PgParam pg_bytes(std::string value) { return {std::move(value), true}; }

std::string pg_string(const PGresult* result, int row, int column) {
  return std::string(PQgetvalue(result, row, column), static_cast<std::size_t>(PQgetlength(result, row, column)));
}

std::int64_t pg_int64(const PGresult* result, int row, int column) {
  return std::stoll(pg_string(result, row, column));
}

bool pg_bool(const PGresult* result, int row, int column) { return PQgetvalue(result, row, column)[0] == 't'; }

std::string pg_bytea(const PGresult* result, int row, int column) {
  std::size_t length = 0;
  unsigned char* bytes =
      PQunescapeBytea(reinterpret_cast<const unsigned char*>(PQgetvalue(result, row, column)), &length);
  if (!bytes) throw Error(ErrorCode::kResourceExhausted, "job_store", "out of memory reading bytea");
  std::string out(reinterpret_cast<const char*>(bytes), length);
  PQfreemem(bytes);
  return out;
}

void check_conninfo(const std::string& conninfo, const std::string& field) {
  char* message = nullptr;
  PQconninfoOption* options = PQconninfoParse(conninfo.c_str(), &message);
  if (!options) {
    const std::string reason = message ? trimmed(message) : "out of memory";
    PQfreemem(message);
    throw_invalid(field, "is not a PostgreSQL connection string (postgresql://... or key=value): " + reason);
  }
  PQconninfoFree(options);
}

namespace {

// libpq's defaults wait for ever: a connect to a host that is gone, and a LISTEN connection to a
// database that vanished without closing TCP (only the kernel's two-hour keepalive notices).
// These come before the conninfo, which overrides any of them (expand_dbname).
PGconn* connect_with_defaults(const std::string& conninfo) {
  const char* const keywords[] = {
      "connect_timeout", "keepalives", "keepalives_idle", "keepalives_interval", "keepalives_count", "dbname", nullptr};
  const char* const values[] = {
      kPgConnectTimeoutS, "1",    kPgKeepalivesIdleS, kPgKeepalivesIntervalS, kPgKeepalivesCount,
      conninfo.c_str(),   nullptr};
  return PQconnectdbParams(keywords, values, /*expand_dbname=*/1);
}

}  // namespace

PgConnection::PgConnection(const std::string& conninfo) : conn_(connect_with_defaults(conninfo)) {
  if (!conn_ || PQstatus(conn_) != CONNECTION_OK) {
    const std::string reason = conn_ ? trimmed(PQerrorMessage(conn_)) : "out of memory";
    PQfinish(conn_);
    conn_ = nullptr;
    throw StoreUnavailable("cannot connect to the PostgreSQL job store: " + reason);
  }
  // Notices (e.g. "relation already exists, skipping") are not ours to print.
  PQsetNoticeProcessor(
      conn_, [](void*, const char*) {}, nullptr);
}

PgConnection::~PgConnection() { PQfinish(conn_); }

PgResult PgConnection::exec(const std::string& sql, const std::vector<PgParam>& params) {
  std::vector<const char*> values;
  std::vector<int> lengths;
  std::vector<int> formats;
  for (const PgParam& param : params) {
    values.push_back(param.value.data());
    lengths.push_back(static_cast<int>(param.value.size()));
    formats.push_back(param.binary ? 1 : 0);
  }
  PgResult result(PQexecParams(conn_, sql.c_str(), static_cast<int>(params.size()), nullptr, values.data(),
                               lengths.data(), formats.data(), 0));
  const ExecStatusType status = result ? PQresultStatus(result.get()) : PGRES_FATAL_ERROR;
  if (status != PGRES_COMMAND_OK && status != PGRES_TUPLES_OK) fail(result.get(), "statement");
  return result;
}

void PgConnection::exec_script(const std::string& sql) {
  PgResult result(PQexec(conn_, sql.c_str()));
  const ExecStatusType status = result ? PQresultStatus(result.get()) : PGRES_FATAL_ERROR;
  if (status != PGRES_COMMAND_OK && status != PGRES_TUPLES_OK) fail(result.get(), "migration");
}

void PgConnection::rollback_quietly() {
  if (!healthy()) return;
  PgResult ignored(PQexec(conn_, "ROLLBACK"));
}

void PgConnection::fail(const PGresult* result, const std::string& what) {
  const std::string sqlstate =
      result && PQresultErrorField(result, PG_DIAG_SQLSTATE) ? PQresultErrorField(result, PG_DIAG_SQLSTATE) : "";
  const std::string message = trimmed(result ? PQresultErrorMessage(result) : PQerrorMessage(conn_));
  const std::string text = what + ": " + (message.empty() ? trimmed(PQerrorMessage(conn_)) : message);
  if (!healthy() || server_away(sqlstate)) {
    throw StoreUnavailable("the PostgreSQL job store is unreachable: " + text);
  }
  // 53100 disk_full, 53200 out_of_memory: resources, as a full SQLite disk is.
  if (sqlstate.rfind("53", 0) == 0) throw Error(ErrorCode::kResourceExhausted, "job_store", text);
  throw Error(ErrorCode::kInternal, "job_store", text);
}

PgPool::PgPool(std::string conninfo, std::size_t size)
    : conninfo_(std::move(conninfo)), size_(std::max<std::size_t>(1, size)) {}

PgPool::~PgPool() = default;

PgPool::Borrowed PgPool::borrow() {
  std::unique_ptr<PgConnection> connection;
  {
    std::unique_lock lock(mu_);
    available_.wait(lock, [this] { return !idle_.empty() || lent_ < size_; });
    ++lent_;
    if (!idle_.empty()) {
      connection = std::move(idle_.back());
      idle_.pop_back();
    }
  }
  if (connection && !connection->healthy()) connection.reset();
  if (!connection) {
    try {
      connection = std::make_unique<PgConnection>(conninfo_);
    } catch (...) {
      give_back(nullptr);
      throw;
    }
  }
  return Borrowed(*this, std::move(connection));
}

void PgPool::drop_idle() {
  std::vector<std::unique_ptr<PgConnection>> stale;
  {
    std::lock_guard lock(mu_);
    stale.swap(idle_);
  }
}

void PgPool::give_back(std::unique_ptr<PgConnection> connection) {
  std::lock_guard lock(mu_);
  --lent_;
  if (connection && connection->healthy()) idle_.push_back(std::move(connection));
  available_.notify_one();
}

}  // namespace posefuse::server
