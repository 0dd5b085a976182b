#pragma once
// The PostgreSQL job store's schema: numbered migrations, applied in order at start by whichever
// replica comes first (under an advisory lock, so that replicas starting together do not race).
// A database whose schema is newer than this binary knows is refused: a newer server has
// changed it, and this one would misread it.
#include <string>

#include "server/pg_connection.hpp"

namespace posefuse::server {

// The schema version this binary writes and reads.
int pg_schema_version();

// Brings the database to pg_schema_version(). Throws kFailedPrecondition (field "--job-store")
// naming both versions for a newer database; StoreUnavailable when it cannot be reached.
void migrate_pg_schema(PgConnection& connection);

}  // namespace posefuse::server
