#pragma once
// Where batch jobs live: their state and their results. The server keeps nothing about a job in
// memory that the store does not have, so a restarted server (or another replica, with a shared
// store) picks up every job: unfinished() lists what was queued or running when it stopped.
// SQLite is the embedded default (sqlite_job_store.hpp); a PostgreSQL store for several replicas
// implements the same interface.
#include <cstdint>
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
};

class JobStore {
 public:
  virtual ~JobStore() = default;

  // A new QUEUED job of tenant `owner` with a fresh unique id; create and update times set to
  // `now_unix_us`.
  virtual v1::Job create(const v1::JobSpec& spec, const std::string& recording_path,
                         const std::string& owner, std::int64_t now_unix_us) = 0;
  virtual std::optional<JobRecord> get(const std::string& job_id) = 0;
  // The jobs of tenant `owner`, newest first. `after_job_id` continues a listing after that job
  // (page token); `states` filters (empty = all). At most `limit` jobs.
  virtual std::vector<v1::Job> list(std::size_t limit, const std::string& after_job_id,
                                    const std::vector<v1::Job::State>& states,
                                    const std::string& owner) = 0;
  // Replaces the stored job of the same id (state, progress, summary, error, update time).
  // Throws kNotFound for an unknown id.
  virtual void update(const v1::Job& job) = 0;

  // Results in order; append continues the sequence.
  virtual void append_results(const std::string& job_id,
                              const std::vector<v1::FitResult>& results) = 0;
  virtual std::vector<v1::FitResult> results(const std::string& job_id) = 0;
  // Drops a job's results (a job restarted from the beginning after a server restart).
  virtual void clear_results(const std::string& job_id) = 0;

  // Jobs QUEUED or RUNNING, oldest first: the work a starting server takes up again.
  virtual std::vector<JobRecord> unfinished() = 0;
};

}  // namespace posefuse::server
