#pragma once
// Runs batch jobs: each job reads its recording from disk and goes through the same
// SessionPipeline as a Fit call, on the worker pool, at most max_running at once. Everything a
// job produces is written to the JobStore as it goes (results in batches, progress in the job),
// so a restarted server loses nothing: resume_unfinished() restarts every job that was queued or
// running (from the beginning; its partial results are dropped first).
//
// Shutdown hands work back: running jobs stop between two chunks and stay RUNNING in the store,
// queued ones stay QUEUED; the next server start resumes them.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>

#include "server/job_store.hpp"
#include "server/metrics.hpp"
#include "server/worker_pool.hpp"

namespace posefuse::server {

bool is_terminal(v1::Job::State state);

class JobRunner {
 public:
  // `recordings_root`: where jobs submitted by reference are opened beneath (empty: off).
  JobRunner(JobStore& store, WorkerPool& pool, Metrics& metrics, unsigned max_running,
            std::filesystem::path recordings_root);
  ~JobRunner();  // stops running jobs (they stay RUNNING in the store) and waits for them

  // Re-queues every unfinished job in the store. Call once at start.
  void resume_unfinished();
  // Stores a new job of tenant `owner` and queues it.
  v1::Job submit(const v1::JobSpec& spec, const std::string& recording_path,
                 const std::string& owner);
  // Cancels a queued or running job of tenant `owner`; a finished job is returned unchanged.
  // nullopt: no such job of that tenant.
  std::optional<v1::Job> cancel(const std::string& job_id, const std::string& owner);

  // Calls `listener` with every later version of the job (from a worker thread) until
  // unsubscribe. Returns a token.
  using Listener = std::function<void(const v1::Job&)>;
  std::uint64_t subscribe(const std::string& job_id, Listener listener);
  void unsubscribe(std::uint64_t token);

  JobStore& store() { return store_; }
  // Waits until no job is running or queued (tests); false on timeout.
  bool wait_idle(std::chrono::milliseconds timeout);

 private:
  void start_next_locked();
  void run(const std::string& job_id);
  void run_job(JobRecord& record);
  void publish(const v1::Job& job);

  JobStore& store_;
  WorkerPool& pool_;
  Metrics& metrics_;
  const unsigned max_running_;
  const std::filesystem::path recordings_root_;
  std::mutex mu_;
  std::condition_variable idle_;
  std::deque<std::string> queue_;
  std::set<std::string> running_;
  std::set<std::string> cancel_requested_;
  bool stopping_ = false;
  std::atomic<bool> stop_flag_{false};
  std::uint64_t next_token_ = 1;
  std::map<std::uint64_t, std::pair<std::string, Listener>> listeners_;
};

}  // namespace posefuse::server
