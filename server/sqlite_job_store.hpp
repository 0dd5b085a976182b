#pragma once
// JobStore in one SQLite database file (WAL mode), for one server process (a second one is
// refused: an flock on <file>.lock). Jobs and results are
// stored as serialised protobuf messages beside the columns that queries need (state, create
// time, the lease). Uploads stay the spooled files in the data dir. Events go to the listener
// of this process only. Thread-safe: one connection, one mutex.
#include <filesystem>
#include <functional>
#include <mutex>

#include "server/job_store.hpp"

struct sqlite3;

namespace posefuse::server {

class SqliteJobStore : public JobStore {
 public:
  // Opens or creates the database. Throws kFailedPrecondition (field = the path) when it cannot.
  explicit SqliteJobStore(const std::filesystem::path& path);
  ~SqliteJobStore() override;
  SqliteJobStore(const SqliteJobStore&) = delete;
  SqliteJobStore& operator=(const SqliteJobStore&) = delete;

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
  void exec(const char* sql);
  bool has_column(const char* table, const char* column);
  // BEGIN IMMEDIATE, body, COMMIT; ROLLBACK when the body throws (which is rethrown).
  template <class Body>
  void in_transaction(Body&& body);
  void append_results_locked(const std::string& job_id, const std::vector<v1::FitResult>& results);
  void clear_results_locked(const std::string& job_id);
  void write_job_locked(const v1::Job& job);
  bool holds_locked(const JobLease& lease);
  void notify(const JobEvent& event);

  std::filesystem::path path_;
  std::mutex mu_;
  sqlite3* db_ = nullptr;
  int lock_fd_ = -1;
  std::mutex listener_mu_;
  std::function<void(const JobEvent&)> listener_;
};

}  // namespace posefuse::server
