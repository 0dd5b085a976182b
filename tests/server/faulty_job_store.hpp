#pragma once
// A JobStore for tests that passes every call to a real SQLite store, except the writes it is
// told to refuse: those throw what SqliteJobStore throws when the disk is full. It also counts
// how results are read, and can hold a job inside the read of its uploaded recording (a slow or
// hung fetch).
#include <atomic>
#include <filesystem>
#include <functional>

#include "common/error.hpp"
#include "server/sqlite_job_store.hpp"

namespace posefuse::server {

class FaultyJobStore : public JobStore {
 public:
  explicit FaultyJobStore(const std::filesystem::path& path) : store_(path) {}

  std::atomic<bool> refuse_creates{false};
  std::atomic<bool> refuse_updates{false};  // a running job's state, and cancelling
  std::atomic<bool> refuse_results{false};
  // Sets refuse_results as the next job is claimed: the disk fills while that job runs.
  std::atomic<bool> refuse_results_after_next_claim{false};
  // What results() handed out: the most results in one call, and the calls.
  std::atomic<std::size_t> largest_results_page{0};
  std::atomic<std::size_t> results_reads{0};
  // Called as a job row is about to be written (set before the server starts).
  std::function<void()> before_create;
  // Called as a job's worker fetches its uploaded recording (set before the server starts).
  std::function<void()> before_fetch;

  v1::Job create(const v1::JobSpec& spec, const std::string& recording_path, const std::string& owner,
                 std::int64_t now_unix_us) override {
    if (before_create) before_create();
    if (refuse_creates) disk_full();
    return store_.create(spec, recording_path, owner, now_unix_us);
  }
  std::optional<JobRecord> get(const std::string& job_id) override { return store_.get(job_id); }
  std::vector<v1::Job> list(std::size_t limit, const std::string& after_job_id,
                            const std::vector<v1::Job::State>& states, const std::string& owner) override {
    return store_.list(limit, after_job_id, states, owner);
  }
  void update(const v1::Job& job) override {
    if (refuse_updates) disk_full();
    store_.update(job);
  }
  void append_results(const std::string& job_id, const std::vector<v1::FitResult>& results) override {
    if (refuse_results) disk_full();
    store_.append_results(job_id, results);
  }
  std::vector<v1::FitResult> results(const std::string& job_id, std::uint64_t first, std::size_t limit) override {
    std::vector<v1::FitResult> page = store_.results(job_id, first, limit);
    std::size_t largest = largest_results_page.load();
    while (page.size() > largest && !largest_results_page.compare_exchange_weak(largest, page.size())) {
    }
    ++results_reads;
    return page;
  }
  std::optional<JobRecord> cancel(const std::string& job_id, const std::string& owner,
                                  std::int64_t now_unix_us) override {
    if (refuse_updates) disk_full();
    return store_.cancel(job_id, owner, now_unix_us);
  }
  std::optional<JobRecord> claim(const std::string& worker, std::chrono::milliseconds lease,
                                 std::int64_t now_unix_us) override {
    std::optional<JobRecord> record = store_.claim(worker, lease, now_unix_us);
    if (record && refuse_results_after_next_claim.exchange(false)) refuse_results = true;
    return record;
  }
  LeaseState renew(const JobLease& lease, std::chrono::milliseconds duration) override {
    return store_.renew(lease, duration);
  }
  void update_running(const JobLease& lease, const v1::Job& job) override {
    if (refuse_updates) disk_full();
    store_.update_running(lease, job);
  }
  void append_results(const JobLease& lease, const std::vector<v1::FitResult>& results) override {
    if (refuse_results) disk_full();
    store_.append_results(lease, results);
  }
  void release(const JobLease& lease, std::int64_t now_unix_us) override { store_.release(lease, now_unix_us); }
  std::vector<ReapedJob> reap(std::uint32_t max_attempts, std::int64_t now_unix_us) override {
    return store_.reap(max_attempts, now_unix_us);
  }
  // A full disk refuses the heartbeat's write as well as the job's.
  void probe() override {
    if (refuse_creates || refuse_updates || refuse_results) disk_full();
    store_.probe();
  }
  void set_event_listener(std::function<void(const JobEvent&)> listener) override {
    store_.set_event_listener(std::move(listener));
  }
  std::string keep_upload(const std::filesystem::path& spooled) override { return store_.keep_upload(spooled); }
  std::filesystem::path local_recording(const std::string& recording_path,
                                        const std::filesystem::path& scratch_dir) override {
    if (before_fetch) before_fetch();
    return store_.local_recording(recording_path, scratch_dir);
  }
  void drop_upload(const std::string& recording_path, const std::filesystem::path& scratch_dir) override {
    store_.drop_upload(recording_path, scratch_dir);
  }

 private:
  [[noreturn]] static void disk_full() {
    throw Error(ErrorCode::kResourceExhausted, "job_store", "step: database or disk is full");
  }
  SqliteJobStore store_;
};

}  // namespace posefuse::server
