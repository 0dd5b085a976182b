#pragma once
// libpq, wrapped: one connection that runs parameterised statements (PQexecParams: values are
// never spliced into SQL text), results freed by RAII, errors as posefuse errors
// (StoreUnavailable when the server cannot be reached, kResourceExhausted for a full disk,
// kInternal otherwise), and a small pool of connections for the store's threads.
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <libpq-fe.h>

namespace posefuse::server {

struct PgResultFree {
  void operator()(PGresult* result) const { PQclear(result); }
};
using PgResult = std::unique_ptr<PGresult, PgResultFree>;

// One statement parameter: text, or bytes sent in binary (bytea).
struct PgParam {
  std::string value;
  bool binary = false;
};
PgParam pg_text(std::string value);
PgParam pg_int(std::int64_t value);
PgParam pg_bytes(std::string value);

// Reading text-format results.
std::string pg_string(const PGresult* result, int row, int column);
std::int64_t pg_int64(const PGresult* result, int row, int column);
bool pg_bool(const PGresult* result, int row, int column);
std::string pg_bytea(const PGresult* result, int row, int column);

// Checks a conninfo ("postgresql://..." or "key=value ..."); throws kInvalidArgument naming
// `field` with libpq's reason.
void check_conninfo(const std::string& conninfo, const std::string& field);

// What every connection gets unless its conninfo says otherwise: a connect gives up after 10 s,
// and a peer that stopped answering is noticed after 30 s idle plus 3 unanswered probes 10 s
// apart (TCP only; a Unix socket needs none).
inline constexpr const char* kPgConnectTimeoutS = "10";
inline constexpr const char* kPgKeepalivesIdleS = "30";
inline constexpr const char* kPgKeepalivesIntervalS = "10";
inline constexpr const char* kPgKeepalivesCount = "3";

class PgConnection {
 public:
  // Connects (with the defaults above); throws StoreUnavailable naming libpq's reason.
  explicit PgConnection(const std::string& conninfo);
  ~PgConnection();
  PgConnection(const PgConnection&) = delete;
  PgConnection& operator=(const PgConnection&) = delete;

  bool healthy() const { return PQstatus(conn_) == CONNECTION_OK; }
  // Runs one statement; throws on any result but a command or tuples result.
  PgResult exec(const std::string& sql, const std::vector<PgParam>& params = {});
  // Several constant statements in one string (migrations); no parameters.
  void exec_script(const std::string& sql);
  // BEGIN, body, COMMIT; ROLLBACK and rethrow when the body throws.
  template <class Body>
  void transaction(Body&& body) {
    exec("BEGIN");
    try {
      body();
      exec("COMMIT");
    } catch (...) {
      rollback_quietly();
      throw;
    }
  }
  PGconn* raw() { return conn_; }

 private:
  void rollback_quietly();
  [[noreturn]] void fail(const PGresult* result, const std::string& what);
  PGconn* conn_ = nullptr;
};

// Connections made on demand, at most `size`, each used by one thread at a time; one that broke
// is replaced on the next borrow.
class PgPool {
 public:
  PgPool(std::string conninfo, std::size_t size);
  ~PgPool();

  class Borrowed {
   public:
    Borrowed(PgPool& pool, std::unique_ptr<PgConnection> connection)
        : pool_(pool), connection_(std::move(connection)) {}
    ~Borrowed() { pool_.give_back(std::move(connection_)); }
    Borrowed(const Borrowed&) = delete;
    Borrowed& operator=(const Borrowed&) = delete;
    PgConnection* operator->() { return connection_.get(); }
    PgConnection& operator*() { return *connection_; }

   private:
    PgPool& pool_;
    std::unique_ptr<PgConnection> connection_;
  };
  // Throws StoreUnavailable when no connection can be made.
  Borrowed borrow();
  // Closes the idle connections (after one broke, the others are likely stale too: the
  // database restarted).
  void drop_idle();

 private:
  void give_back(std::unique_ptr<PgConnection> connection);

  const std::string conninfo_;
  const std::size_t size_;
  std::mutex mu_;
  std::condition_variable available_;
  std::vector<std::unique_ptr<PgConnection>> idle_;
  std::size_t lent_ = 0;
};

}  // namespace posefuse::server
