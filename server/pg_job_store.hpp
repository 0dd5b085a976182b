#pragma once
// JobStore in PostgreSQL, shared by every replica (docs/server.md "Job store"). Jobs, results
// and uploaded recordings (in 1 MiB bytea rows) live in the database, so any replica serves any
// job call and any worker runs any job. claim() takes the oldest QUEUED job with
// FOR UPDATE SKIP LOCKED, so two workers never take the same one; lease times are the
// database's clock (replicas' clocks do not matter). Every change is announced with NOTIFY on
// one channel and heard by every replica's listener (events in job_store.hpp). The schema is
// migrated at start (pg_schema.hpp).
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>

#include "server/job_store.hpp"
#include "server/pg_connection.hpp"
#include "server/pg_listener.hpp"

namespace posefuse::server {

// Whether --job-store names a PostgreSQL database (a postgresql:// or postgres:// URI, or a
// key=value conninfo).
bool is_postgres_conninfo(const std::string& job_store);

class PgJobStore : public JobStore {
 public:
  // Connects and migrates. Throws kInvalidArgument (field "--job-store") for a malformed
  // conninfo, StoreUnavailable when the database cannot be reached, kFailedPrecondition for a
  // schema newer than this binary's.
  explicit PgJobStore(const std::string& conninfo, std::size_t connections = 4);
  ~PgJobStore() override;

  v1::Job create(const v1::JobSpec& spec, const std::string& recording_path, const std::string& owner,
                 std::int64_t now_unix_us) override;
  std::optional<JobRecord> get(const std::string& job_id) override;
  std::vector<v1::Job> list(std::size_t limit, const std::string& after_job_id,
                            const std::vector<v1::Job::State>& states, const std::string& owner) override;
  void update(const v1::Job& job) override;
  void append_results(const std::string& job_id, const std::vector<v1::FitResult>& results) override;
  std::vector<v1::FitResult> results(const std::string& job_id, std::uint64_t first, std::size_t limit) override;
  std::optional<JobRecord> cancel(const std::string& job_id, const std::string& owner,
                                  std::int64_t now_unix_us) override;
  std::optional<JobRecord> claim(const std::string& worker, std::chrono::milliseconds lease,
                                 std::int64_t now_unix_us) override;
  LeaseState renew(const JobLease& lease, std::chrono::milliseconds duration) override;
  void update_running(const JobLease& lease, const v1::Job& job) override;
  void append_results(const JobLease& lease, const std::vector<v1::FitResult>& results) override;
  void release(const JobLease& lease, std::int64_t now_unix_us) override;
  std::vector<ReapedJob> reap(std::uint32_t max_attempts, std::int64_t now_unix_us) override;
  void probe() override;
  void set_event_listener(std::function<void(const JobEvent&)> listener) override;
  std::string keep_upload(const std::filesystem::path& spooled) override;
  std::filesystem::path local_recording(const std::string& recording_path,
                                        const std::filesystem::path& scratch_dir) override;
  void drop_upload(const std::string& recording_path, const std::filesystem::path& scratch_dir) override;

 private:
  // Runs body(connection) on a pooled connection; with `retry`, once more on a fresh one when
  // the first was stale (the database restarted): only for statements safe to repeat.
  template <class Body>
  auto run(bool retry, Body&& body);
  void on_notification(const std::string& payload);
  void deliver(const JobEvent& event);

  PgPool pool_;
  std::mutex listener_mu_;
  std::function<void(const JobEvent&)> listener_;
  std::unique_ptr<PgListener> notifications_;  // last: its thread calls into the members above
};

}  // namespace posefuse::server
