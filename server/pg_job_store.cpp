#include "server/pg_job_store.hpp"

#include <fstream>

#include "common/error.hpp"
#include "server/job_store_errors.hpp"
#include "server/job_transitions.hpp"
#include "server/pg_schema.hpp"
#include "server/random_id.hpp"

namespace posefuse::server {

namespace {

constexpr const char* kChannel = "posefuse_jobs";
constexpr const char* kUploadPrefix = "postgresql-upload:";
constexpr std::size_t kUploadRowBytes = 1 << 20;

constexpr const char* kRecordColumns = "job, recording_path, owner, attempts";
// A lease's WHERE clause; $1 job id, $2 worker, $3 attempt.
constexpr const char* kHeld = "id = $1 AND lease_owner = $2 AND attempts = $3 AND state = 2";
constexpr const char* kLeaseEnd = "clock_timestamp() + $4::double precision * interval '1 millisecond'";

JobRecord read_record(const PGresult* result, int row, int first_column = 0) {
  return {parse_stored_job(pg_bytea(result, row, first_column), "job_store.jobs.job"),
          pg_string(result, row, first_column + 1), pg_string(result, row, first_column + 2),
          static_cast<std::uint32_t>(pg_int64(result, row, first_column + 3))};
}

std::vector<PgParam> lease_params(const JobLease& lease) {
  return {pg_text(lease.job_id), pg_text(lease.worker), pg_int(lease.attempt)};
}

void notify(PgConnection& connection, const char* kind, const std::string& job_id) {
  connection.exec("SELECT pg_notify($1, $2)", {pg_text(kChannel), pg_text(std::string(kind) + " " + job_id)});
}

void write_job(PgConnection& connection, const v1::Job& job) {
  connection.exec("UPDATE jobs SET state = $2, job = $3 WHERE id = $1",
                  {pg_text(job.job_id()), pg_int(job.state()), pg_bytes(job.SerializeAsString())});
}

// Locks the job's row when `lease` holds it; throws LeaseLost otherwise.
void lock_held(PgConnection& connection, const JobLease& lease) {
  PgResult held =
      connection.exec(std::string("SELECT 1 FROM jobs WHERE ") + kHeld + " FOR UPDATE", lease_params(lease));
  if (PQntuples(held.get()) == 0) throw LeaseLost(lease.job_id);
}

void insert_results(PgConnection& connection, const std::string& job_id, const std::vector<v1::FitResult>& results) {
  PgResult next = connection.exec("SELECT COALESCE(MAX(seq) + 1, 0) FROM results WHERE job_id = $1", {pg_text(job_id)});
  std::int64_t seq = pg_int64(next.get(), 0, 0);
  for (const v1::FitResult& result : results) {
    connection.exec("INSERT INTO results (job_id, seq, result) VALUES ($1, $2, $3)",
                    {pg_text(job_id), pg_int(seq++), pg_bytes(result.SerializeAsString())});
  }
}

}  // namespace

bool is_postgres_conninfo(const std::string& job_store) {
  return job_store.rfind("postgresql://", 0) == 0 || job_store.rfind("postgres://", 0) == 0 ||
         job_store.find('=') != std::string::npos;
}

PgJobStore::PgJobStore(const std::string& conninfo, std::size_t connections) : pool_(conninfo, connections) {
  check_conninfo(conninfo, "--job-store");
  {
    PgPool::Borrowed connection = pool_.borrow();
    migrate_pg_schema(*connection);
  }
  notifications_ = std::make_unique<PgListener>(
      conninfo, kChannel, [this](const std::string& payload) { on_notification(payload); },
      [this] {
        deliver({JobEvent::Kind::kMissedEvents, ""});
      });
}

PgJobStore::~PgJobStore() { notifications_.reset(); }

template <class Body>
auto PgJobStore::run(bool retry, Body&& body) {
  try {
    PgPool::Borrowed connection = pool_.borrow();
    return body(*connection);
  } catch (const StoreUnavailable&) {
    pool_.drop_idle();
    if (!retry) throw;
  }
  PgPool::Borrowed connection = pool_.borrow();
  return body(*connection);
}

v1::Job PgJobStore::create(const v1::JobSpec& spec, const std::string& recording_path, const std::string& owner,
                           std::int64_t now_unix_us) {
  const v1::Job job = new_job(spec, now_unix_us);
  run(false, [&](PgConnection& c) {
    c.transaction([&] {
      c.exec("INSERT INTO jobs (id, owner, state, recording_path, job) VALUES ($1, $2, $3, $4, $5)",
             {pg_text(job.job_id()), pg_text(owner), pg_int(job.state()), pg_text(recording_path),
              pg_bytes(job.SerializeAsString())});
      notify(c, "queued", job.job_id());
    });
  });
  return job;
}

std::optional<JobRecord> PgJobStore::get(const std::string& job_id) {
  return run(true, [&](PgConnection& c) -> std::optional<JobRecord> {
    PgResult row = c.exec(std::string("SELECT ") + kRecordColumns + " FROM jobs WHERE id = $1", {pg_text(job_id)});
    if (PQntuples(row.get()) == 0) return std::nullopt;
    return read_record(row.get(), 0);
  });
}

std::vector<v1::Job> PgJobStore::list(std::size_t limit, const std::string& after_job_id,
                                      const std::vector<v1::Job::State>& states, const std::string& owner) {
  std::string state_array = "{";
  for (std::size_t i = 0; i < states.size(); ++i) {
    state_array += (i ? "," : "") + std::to_string(static_cast<int>(states[i]));
  }
  state_array += "}";
  return run(true, [&](PgConnection& c) {
    PgResult rows = c.exec(
        "SELECT job FROM jobs WHERE owner = $1"
        " AND ($2 = '' OR seq < (SELECT seq FROM jobs WHERE id = $2))"
        " AND (cardinality($3::integer[]) = 0 OR state = ANY($3::integer[]))"
        " ORDER BY seq DESC LIMIT $4",
        {pg_text(owner), pg_text(after_job_id), pg_text(state_array), pg_int(static_cast<std::int64_t>(limit))});
    std::vector<v1::Job> jobs;
    for (int i = 0; i < PQntuples(rows.get()); ++i) {
      jobs.push_back(parse_stored_job(pg_bytea(rows.get(), i, 0), "job_store.jobs.job"));
    }
    return jobs;
  });
}

void PgJobStore::update(const v1::Job& job) {
  run(false, [&](PgConnection& c) {
    c.transaction([&] {
      PgResult updated = c.exec("UPDATE jobs SET state = $2, job = $3 WHERE id = $1 RETURNING id",
                                {pg_text(job.job_id()), pg_int(job.state()), pg_bytes(job.SerializeAsString())});
      if (PQntuples(updated.get()) == 0) {
        throw Error(ErrorCode::kNotFound, "job_id", "no job '" + job.job_id() + "'");
      }
      notify(c, "changed", job.job_id());
    });
  });
}

void PgJobStore::append_results(const std::string& job_id, const std::vector<v1::FitResult>& results) {
  run(false, [&](PgConnection& c) { c.transaction([&] { insert_results(c, job_id, results); }); });
}

std::vector<v1::FitResult> PgJobStore::results(const std::string& job_id, std::uint64_t first, std::size_t limit) {
  return run(true, [&](PgConnection& c) {
    PgResult rows =
        c.exec("SELECT result FROM results WHERE job_id = $1 AND seq >= $2 ORDER BY seq LIMIT $3",
               {pg_text(job_id), pg_int(static_cast<std::int64_t>(first)), pg_int(static_cast<std::int64_t>(limit))});
    std::vector<v1::FitResult> results(static_cast<std::size_t>(PQntuples(rows.get())));
    for (int i = 0; i < PQntuples(rows.get()); ++i) {
      if (!results[static_cast<std::size_t>(i)].ParseFromString(pg_bytea(rows.get(), i, 0))) {
        throw Error(ErrorCode::kDataLoss, "job_store.results", "stored result does not parse");
      }
    }
    return results;
  });
}

std::optional<JobRecord> PgJobStore::cancel(const std::string& job_id, const std::string& owner,
                                            std::int64_t now_unix_us) {
  return run(false, [&](PgConnection& c) {
    std::optional<JobRecord> record;
    c.transaction([&] {
      PgResult row =
          c.exec(std::string("SELECT ") + kRecordColumns + " FROM jobs WHERE id = $1 FOR UPDATE", {pg_text(job_id)});
      if (PQntuples(row.get()) == 0) return;
      record = read_record(row.get(), 0);
      if (record->owner != owner) {
        record.reset();
        return;
      }
      if (record->job.state() == v1::Job::QUEUED) {
        mark_cancelled(record->job, now_unix_us);
        write_job(c, record->job);
        notify(c, "changed", job_id);
      } else if (record->job.state() == v1::Job::RUNNING) {
        c.exec("UPDATE jobs SET cancel_requested = true WHERE id = $1", {pg_text(job_id)});
        notify(c, "cancel", job_id);
      }
    });
    return record;
  });
}

std::optional<JobRecord> PgJobStore::claim(const std::string& worker, std::chrono::milliseconds lease,
                                           std::int64_t now_unix_us) {
  return run(false, [&](PgConnection& c) {
    std::optional<JobRecord> record;
    c.transaction([&] {
      PgResult row = c.exec(std::string("SELECT ") + kRecordColumns +
                            " FROM jobs WHERE state = 1 ORDER BY seq LIMIT 1 FOR UPDATE SKIP LOCKED");
      if (PQntuples(row.get()) == 0) return;
      record = read_record(row.get(), 0);
      record->attempts += 1;
      mark_claimed(record->job, now_unix_us);
      const std::string& id = record->job.job_id();
      c.exec("DELETE FROM results WHERE job_id = $1", {pg_text(id)});
      c.exec(std::string("UPDATE jobs SET state = 2, job = $5, attempts = $3, lease_owner = $2,"
                         " lease_expires = ") +
                 kLeaseEnd + ", cancel_requested = false WHERE id = $1",
             {pg_text(id), pg_text(worker), pg_int(record->attempts), pg_int(lease.count()),
              pg_bytes(record->job.SerializeAsString())});
      notify(c, "changed", id);
    });
    return record;
  });
}

LeaseState PgJobStore::renew(const JobLease& lease, std::chrono::milliseconds duration) {
  return run(true, [&](PgConnection& c) {
    std::vector<PgParam> params = lease_params(lease);
    params.push_back(pg_int(duration.count()));
    PgResult row = c.exec(
        std::string("UPDATE jobs SET lease_expires = ") + kLeaseEnd + " WHERE " + kHeld + " RETURNING cancel_requested",
        params);
    if (PQntuples(row.get()) == 0) return LeaseState::kLost;
    return pg_bool(row.get(), 0, 0) ? LeaseState::kCancelRequested : LeaseState::kHeld;
  });
}

void PgJobStore::update_running(const JobLease& lease, const v1::Job& job) {
  run(false, [&](PgConnection& c) {
    c.transaction([&] {
      lock_held(c, lease);
      write_job(c, job);
      if (is_terminal(job.state())) {
        c.exec("UPDATE jobs SET lease_owner = '', lease_expires = NULL WHERE id = $1", {pg_text(lease.job_id)});
      }
      notify(c, "changed", lease.job_id);
    });
  });
}

void PgJobStore::append_results(const JobLease& lease, const std::vector<v1::FitResult>& results) {
  run(false, [&](PgConnection& c) {
    c.transaction([&] {
      lock_held(c, lease);
      insert_results(c, lease.job_id, results);
    });
  });
}

void PgJobStore::release(const JobLease& lease, std::int64_t now_unix_us) {
  run(false, [&](PgConnection& c) {
    c.transaction([&] {
      PgResult row = c.exec(std::string("SELECT job FROM jobs WHERE ") + kHeld + " FOR UPDATE", lease_params(lease));
      if (PQntuples(row.get()) == 0) return;
      v1::Job job = parse_stored_job(pg_bytea(row.get(), 0, 0), "job_store.jobs.job");
      mark_queued_again(job, now_unix_us);
      c.exec(
          "UPDATE jobs SET state = 1, job = $2, attempts = attempts - 1, lease_owner = '',"
          " lease_expires = NULL WHERE id = $1",
          {pg_text(lease.job_id), pg_bytes(job.SerializeAsString())});
      c.exec("DELETE FROM results WHERE job_id = $1", {pg_text(lease.job_id)});
      notify(c, "queued", lease.job_id);
    });
  });
}

std::vector<ReapedJob> PgJobStore::reap(std::uint32_t max_attempts, std::int64_t now_unix_us) {
  return run(true, [&](PgConnection& c) {
    std::vector<ReapedJob> reaped;
    c.transaction([&] {
      reaped.clear();
      PgResult rows = c.exec(std::string("SELECT ") + kRecordColumns +
                             ", cancel_requested FROM jobs WHERE state = 2 AND"
                             " COALESCE(lease_expires, '-infinity') < clock_timestamp()"
                             " ORDER BY seq FOR UPDATE SKIP LOCKED");
      for (int i = 0; i < PQntuples(rows.get()); ++i) {
        JobRecord record = read_record(rows.get(), i);
        const v1::Job::State state =
            mark_lease_expired(record.job, record.attempts, max_attempts, pg_bool(rows.get(), i, 4), now_unix_us);
        const std::string& id = record.job.job_id();
        write_job(c, record.job);
        c.exec("UPDATE jobs SET lease_owner = '', lease_expires = NULL WHERE id = $1", {pg_text(id)});
        if (state == v1::Job::QUEUED) c.exec("DELETE FROM results WHERE job_id = $1", {pg_text(id)});
        notify(c, state == v1::Job::QUEUED ? "queued" : "changed", id);
        reaped.push_back({id, state});
      }
    });
    return reaped;
  });
}

// A round trip, not a write: PostgreSQL's failures are mostly the database being away, and a
// write would need a table of its own in the shared schema.
void PgJobStore::probe() {
  run(false, [&](PgConnection& c) { c.exec("SELECT 1"); });
}

void PgJobStore::set_event_listener(std::function<void(const JobEvent&)> listener) {
  std::lock_guard lock(listener_mu_);
  listener_ = std::move(listener);
}

void PgJobStore::deliver(const JobEvent& event) {
  std::lock_guard lock(listener_mu_);
  if (listener_) listener_(event);
}

void PgJobStore::on_notification(const std::string& payload) {
  const auto space = payload.find(' ');
  if (space == std::string::npos) return;
  const std::string kind = payload.substr(0, space);
  const std::string job_id = payload.substr(space + 1);
  if (kind == "queued") deliver({JobEvent::Kind::kQueued, job_id});
  else if (kind == "changed") deliver({JobEvent::Kind::kChanged, job_id});
  else if (kind == "cancel") deliver({JobEvent::Kind::kCancelRequested, job_id});
}

std::string PgJobStore::keep_upload(const std::filesystem::path& spooled) {
  const std::string upload_id = random_hex_id();
  std::ifstream in(spooled, std::ios::binary);
  if (!in) throw Error(ErrorCode::kInternal, "upload", "cannot read the spooled upload back");
  run(false, [&](PgConnection& c) {
    c.transaction([&] {
      std::string piece(kUploadRowBytes, '\0');
      for (std::int64_t seq = 0; in; ++seq) {
        in.read(piece.data(), static_cast<std::streamsize>(piece.size()));
        const auto got = static_cast<std::size_t>(in.gcount());
        if (got == 0) break;
        c.exec("INSERT INTO uploads (upload_id, seq, data) VALUES ($1, $2, $3)",
               {pg_text(upload_id), pg_int(seq), pg_bytes(piece.substr(0, got))});
      }
      if (in.bad()) throw Error(ErrorCode::kInternal, "upload", "cannot read the spooled upload back");
    });
  });
  std::error_code ignored;
  std::filesystem::remove(spooled, ignored);
  return kUploadPrefix + upload_id;
}

std::filesystem::path PgJobStore::local_recording(const std::string& recording_path,
                                                  const std::filesystem::path& scratch_dir) {
  if (recording_path.rfind(kUploadPrefix, 0) != 0) return recording_path;
  const std::string upload_id = recording_path.substr(std::string(kUploadPrefix).size());
  const std::filesystem::path local = scratch_dir / (upload_id + ".pfchunks");
  std::filesystem::path partial = local;
  partial += ".partial";
  {
    std::ofstream out(partial, std::ios::binary | std::ios::trunc);
    if (!out) throw Error(ErrorCode::kInternal, "recording", "cannot write to the scratch folder");
    // Row by row: an upload may be far larger than memory.
    for (std::int64_t seq = 0;; ++seq) {
      const std::string bytes = run(true, [&](PgConnection& c) -> std::string {
        PgResult row =
            c.exec("SELECT data FROM uploads WHERE upload_id = $1 AND seq = $2", {pg_text(upload_id), pg_int(seq)});
        return PQntuples(row.get()) == 0 ? std::string() : pg_bytea(row.get(), 0, 0);
      });
      if (bytes.empty()) {
        if (seq == 0) {
          throw Error(ErrorCode::kNotFound, "recording", "the uploaded recording is not in the job store");
        }
        break;
      }
      out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    }
    if (!out.flush())
      throw Error(ErrorCode::kResourceExhausted, "recording", "cannot write the scratch copy (disk full?)");
  }
  std::filesystem::rename(partial, local);
  return local;
}

void PgJobStore::drop_upload(const std::string& recording_path, const std::filesystem::path& scratch_dir) {
  if (recording_path.rfind(kUploadPrefix, 0) != 0) return;
  const std::string upload_id = recording_path.substr(std::string(kUploadPrefix).size());
  std::error_code ignored;
  std::filesystem::remove(scratch_dir / (upload_id + ".pfchunks"), ignored);
  run(false, [&](PgConnection& c) { c.exec("DELETE FROM uploads WHERE upload_id = $1", {pg_text(upload_id)}); });
}

}  // namespace posefuse::server
