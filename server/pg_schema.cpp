#include "server/pg_schema.hpp"

#include <array>

#include "common/error.hpp"
#include "server/job_store_errors.hpp"

namespace posefuse::server {

namespace {

// Migration i takes the schema from version i to i + 1. Never edit one that has shipped:
// append another.
constexpr std::array<const char*, 1> kMigrations = {
    // 1: jobs with their lease, results, uploads in chunks.
    "CREATE TABLE jobs ("
    "  seq bigserial PRIMARY KEY,"
    "  id text UNIQUE NOT NULL,"
    "  owner text NOT NULL,"
    "  state integer NOT NULL,"
    "  recording_path text NOT NULL,"
    "  job bytea NOT NULL,"
    "  attempts integer NOT NULL DEFAULT 0,"
    "  lease_owner text NOT NULL DEFAULT '',"
    "  lease_expires timestamptz,"
    "  cancel_requested boolean NOT NULL DEFAULT false);"
    "CREATE INDEX jobs_by_owner ON jobs (owner, seq DESC);"
    "CREATE INDEX jobs_by_state ON jobs (state, seq);"
    "CREATE TABLE results ("
    "  job_id text NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,"
    "  seq integer NOT NULL,"
    "  result bytea NOT NULL,"
    "  PRIMARY KEY (job_id, seq));"
    "CREATE TABLE uploads ("
    "  upload_id text NOT NULL,"
    "  seq integer NOT NULL,"
    "  data bytea NOT NULL,"
    "  PRIMARY KEY (upload_id, seq));",
};

// Any constant; it only has to be the same in every replica.
constexpr const char* kMigrationLock = "SELECT pg_advisory_xact_lock(7085113723)";

}  // namespace

int pg_schema_version() { return static_cast<int>(kMigrations.size()); }

void migrate_pg_schema(PgConnection& connection) {
  connection.transaction([&] {
    connection.exec(kMigrationLock);
    connection.exec("CREATE TABLE IF NOT EXISTS posefuse_schema (version integer NOT NULL)");
    PgResult current = connection.exec("SELECT version FROM posefuse_schema");
    int version = 0;
    if (PQntuples(current.get()) == 0) {
      connection.exec("INSERT INTO posefuse_schema (version) VALUES (0)");
    } else {
      version = static_cast<int>(pg_int64(current.get(), 0, 0));
    }
    if (version > pg_schema_version()) {
      throw StoreMisconfigured("--job-store", "the database's posefuse schema is version " + std::to_string(version) +
                                                  ", newer than this posefuse-server knows (" +
                                                  std::to_string(pg_schema_version()) +
                                                  "): a newer server has migrated it; run that version or a newer one");
    }
    for (; version < pg_schema_version(); ++version) {
      connection.exec_script(kMigrations[static_cast<std::size_t>(version)]);
      connection.exec("UPDATE posefuse_schema SET version = $1", {pg_int(version + 1)});
    }
  });
}

}  // namespace posefuse::server
