#pragma once
// A JobStore that opens the real one when it can. The server starts, and serves Fit, when the job
// store cannot be opened yet (a full disk, a file where the database's folder should be,
// PostgreSQL away): until it opens, every call throws StoreUnavailable naming why (the job calls
// answer UNAVAILABLE), and probe(), which the job runner calls on every heartbeat, tries to open
// it again. Once open it stays open and every call goes through to it.
#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <string>

#include "server/job_store.hpp"

namespace posefuse::server {

class DeferredJobStore : public JobStore {
 public:
  using Opener = std::function<std::unique_ptr<JobStore>()>;
  // Tries to open at once. Rethrows what can never pass (StoreMisconfigured, kInvalidArgument):
  // the server then does not start.
  explicit DeferredJobStore(Opener open);

  // Why the store is not open; empty once it is.
  std::string problem();

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
  // Opens the store if it is not open yet, then probes it.
  void probe() override;
  void set_event_listener(std::function<void(const JobEvent&)> listener) override;
  std::string keep_upload(const std::filesystem::path& spooled) override;
  std::filesystem::path local_recording(const std::string& recording_path,
                                        const std::filesystem::path& scratch_dir) override;
  void drop_upload(const std::string& recording_path, const std::filesystem::path& scratch_dir) override;

 private:
  // Throws StoreUnavailable while the store is not open.
  JobStore& store();
  // Throws StoreUnavailable naming why the store cannot be opened (or rethrows, at the first
  // try, what never passes).
  void open(bool first_try);

  Opener open_;
  std::mutex mu_;  // opening, the listener and the problem
  std::unique_ptr<JobStore> opened_;
  std::atomic<JobStore*> store_{nullptr};  // opened_, once it is set
  std::string problem_;
  std::function<void(const JobEvent&)> listener_;
};

}  // namespace posefuse::server
