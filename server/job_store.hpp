#pragma once
// Where batch jobs live: their state, their results, the queue workers claim them from and the
// uploads they read. The server keeps nothing about a job in memory that the store does not
// have, so a restarted server (or another replica, with a shared store) picks up every job.
//
// A worker runs a job under a lease: claim() hands it the oldest QUEUED job with a lease that
// renew() extends (a heartbeat); a job whose lease expired (its worker was killed or lost the
// database) goes back to the queue through reap(), or fails once it has been claimed
// max_attempts times. Every write of a running job carries its JobLease, so a worker that lost
// its lease cannot write over the attempt that took the job over.
//
// SQLite is the embedded default for one process (sqlite_job_store.hpp); PostgreSQL is the
// shared store for several replicas (pg_job_store.hpp). Lease times are the store's own clock.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "posefuse/v1/results.pb.h"
#include "posefuse/v1/service.pb.h"

namespace posefuse::server {

struct JobRecord {
  v1::Job job;
  std::string recording_path;  // what the runner reads (resolved by the server, not the client)
  std::string owner;           // the tenant that submitted it ("" without tenants)
  std::uint32_t attempts = 0;  // how often it has been claimed
};

// The claim a worker holds on a running job.
struct JobLease {
  std::string job_id;
  std::string worker;         // the claiming worker's id
  std::uint32_t attempt = 0;  // the claim this lease is (JobRecord::attempts after claim)
};

enum class LeaseState { kHeld, kCancelRequested, kLost };

// What the store tells every replica about (PostgreSQL: LISTEN/NOTIFY).
struct JobEvent {
  enum class Kind {
    kQueued,           // a job can be claimed
    kChanged,          // a job's stored state changed
    kCancelRequested,  // a running job is to stop
    kMissedEvents,     // events may have been lost (the connection was down): re-read
  };
  Kind kind;
  std::string job_id;  // empty for kMissedEvents
};

// What reap() did with a job whose lease had expired.
struct ReapedJob {
  std::string job_id;
  v1::Job::State state;  // QUEUED again, FAILED (attempts used up) or CANCELLED (was requested)
};

class JobStore {
 public:
  virtual ~JobStore() = default;

  // A new QUEUED job of tenant `owner` with a fresh unique id; create and update times set to
  // `now_unix_us`.
  virtual v1::Job create(const v1::JobSpec& spec, const std::string& recording_path, const std::string& owner,
                         std::int64_t now_unix_us) = 0;
  virtual std::optional<JobRecord> get(const std::string& job_id) = 0;
  // The jobs of tenant `owner`, newest first. `after_job_id` continues a listing after that job
  // (page token); `states` filters (empty = all). At most `limit` jobs.
  virtual std::vector<v1::Job> list(std::size_t limit, const std::string& after_job_id,
                                    const std::vector<v1::Job::State>& states, const std::string& owner) = 0;
  // Replaces the stored job of the same id whatever holds it (tests and tools set up states
  // with it; workers write through update_running). Throws kNotFound for an unknown id.
  virtual void update(const v1::Job& job) = 0;
  // Results in order; append continues the sequence (unfenced, as update).
  virtual void append_results(const std::string& job_id, const std::vector<v1::FitResult>& results) = 0;
  // One page of a job's results, in order: at most `limit` from the `first` (0 = the first
  // result). Callers read page by page, so that a job's results are never all in memory.
  virtual std::vector<v1::FitResult> results(const std::string& job_id, std::uint64_t first, std::size_t limit) = 0;

  // Cancels a job of tenant `owner`: a QUEUED one becomes CANCELLED at once, a RUNNING one is
  // marked so that its worker stops it (kCancelRequested); a finished one is left alone. Returns
  // the job as stored afterwards; nullopt when there is no such job of that tenant.
  virtual std::optional<JobRecord> cancel(const std::string& job_id, const std::string& owner,
                                          std::int64_t now_unix_us) = 0;

  // The oldest QUEUED job, now RUNNING under a lease of `lease` for `worker`, its attempts
  // counted and any results of an earlier attempt dropped. nullopt when none is queued.
  virtual std::optional<JobRecord> claim(const std::string& worker, std::chrono::milliseconds lease,
                                         std::int64_t now_unix_us) = 0;
  // Extends a held lease by `lease` from now.
  virtual LeaseState renew(const JobLease& lease, std::chrono::milliseconds duration) = 0;
  // The holder's writes. Throw kAborted when `lease` no longer holds the job. A terminal state
  // ends the lease.
  virtual void update_running(const JobLease& lease, const v1::Job& job) = 0;
  virtual void append_results(const JobLease& lease, const std::vector<v1::FitResult>& results) = 0;
  // Hands the job back (a server stopping): QUEUED again, this attempt not counted, its results
  // dropped.
  virtual void release(const JobLease& lease, std::int64_t now_unix_us) = 0;
  // Jobs whose lease has expired: QUEUED again (results dropped) while attempts <
  // max_attempts, FAILED (ABORTED, the message says why) when all are used up, CANCELLED when a
  // cancel was requested.
  virtual std::vector<ReapedJob> reap(std::uint32_t max_attempts, std::int64_t now_unix_us) = 0;

  // A small write, made on every heartbeat: throws what a job's write would throw while the
  // store cannot take writes (a full disk, PostgreSQL away), and returns once it can again.
  // The jobs' health service follows it (docs/server.md, "Health and reflection").
  virtual void probe() = 0;

  // Where events go (called from any thread, never while a store lock is held); set once
  // before use, cleared ({}) before the listener goes away. Clearing waits for a call in
  // progress.
  virtual void set_event_listener(std::function<void(const JobEvent&)> listener) = 0;

  // Uploaded recordings. keep_upload takes the spooled chunk file of a finished upload and
  // returns the recording path to store with its job (the store may move the bytes into
  // itself); local_recording gives a path the runner can open (fetching into `scratch_dir` if
  // needed); drop_upload deletes an upload once its job has finished.
  virtual std::string keep_upload(const std::filesystem::path& spooled) = 0;
  virtual std::filesystem::path local_recording(const std::string& recording_path,
                                                const std::filesystem::path& scratch_dir) = 0;
  virtual void drop_upload(const std::string& recording_path, const std::filesystem::path& scratch_dir) = 0;
};

}  // namespace posefuse::server
