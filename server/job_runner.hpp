#pragma once
// Runs batch jobs: each job reads its recording and goes through the same SessionPipeline as a
// Fit call, at most max_running at once, on this runner's own threads: a long or stuck job never
// holds a thread that Fit calls and uploads need (those run on the server's WorkerPool).
//
// The queue is the JobStore: a dispatcher thread claims jobs under a lease (job_store.hpp),
// renews the leases of the jobs it runs every heartbeat, and reaps jobs whose lease expired
// (their worker was killed), so any number of runners on one shared store run every job exactly
// once at a time. Everything a job produces is written to the store as it goes, through its
// lease.
//
// The heartbeat also probes the store with a small write (JobStore::probe): while it fails no
// job is claimed and the jobs' health is NOT_SERVING (docs/server.md, "Job store").
//
// Watchers (WatchJob) and cancellation follow the store's events, so they work whichever
// replica runs the job. Shutdown hands work back: running jobs stop between two chunks and are
// released to the queue for another worker (or the next start).
//
// A watchdog bounds each attempt: past its deadline, or after too long without reading a chunk,
// the job stops between two chunks and fails with DEADLINE_EXCEEDED. A stop (those, or a
// cancel) that the job's thread does not honour by the next heartbeat means the thread is
// blocked inside a read or a write: the dispatcher then writes the job's end itself, which ends
// the lease, so nothing the thread writes when (if ever) it returns is stored. Such a thread
// keeps its slot of max_running until it returns.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>

#include "server/job_store.hpp"
#include "server/job_transitions.hpp"
#include "server/metrics.hpp"
#include "server/worker_pool.hpp"

namespace posefuse::server {

struct JobRunnerOptions {
  unsigned max_running = 1;
  bool claims_jobs = true;                // false: a replica that serves the API only
  std::filesystem::path recordings_root;  // jobs by reference open beneath it (empty: off)
  std::filesystem::path scratch_dir;      // where uploads held by the store are fetched to
  std::chrono::milliseconds lease{30000};
  std::chrono::milliseconds heartbeat{10000};  // lease renewal, reaping and queue polling
  std::uint32_t max_attempts = 3;
  std::uint64_t max_held_bytes = 0;       // a job's memory budget (session::PipelineOptions)
  std::chrono::milliseconds deadline{0};  // an attempt's longest run; zero: none
  std::chrono::milliseconds stall{0};     // longest time without reading a chunk; zero: none
};

class JobRunner {
 public:
  JobRunner(JobStore& store, Metrics& metrics, JobRunnerOptions options);
  ~JobRunner();  // stop() without a bound

  // Stops claiming and hands running jobs back (each stops between chunks and goes back to the
  // queue), waiting at most `bound` for them. Returns the ids of the jobs still running then:
  // each blocked inside a read that does not return. Their leases expire and another worker
  // resumes them; the caller must not destroy this runner while they run (the server exits
  // instead, docs/server.md "Job store").
  std::vector<std::string> stop(std::chrono::milliseconds bound);

  // Whether the store takes writes: called on every change, from the dispatcher or a worker.
  // The heartbeat's probe (JobStore::probe) decides it, and a job's store write that failed
  // turns it off at once (until the next probe).
  using StoreHealthListener = std::function<void(bool serving)>;
  // Starts the heartbeat, and claiming with claims_jobs. Call once, when the server serves.
  void start(StoreHealthListener on_store_health = {});
  // Why the store does not take writes now (the last probe's or job write's error); empty
  // while it does.
  std::string store_problem();
  // Stores a new job of tenant `owner`; any worker on the store may run it.
  v1::Job submit(const v1::JobSpec& spec, const std::string& recording_path, const std::string& owner);
  // Cancels a queued or running job of tenant `owner` (a running one stops on its worker,
  // wherever that is); a finished job is returned unchanged. nullopt: no such job of that tenant.
  std::optional<v1::Job> cancel(const std::string& job_id, const std::string& owner);

  // Calls `listener` with later versions of the job (from the store's event thread) until
  // unsubscribe. Returns a token.
  using Listener = std::function<void(const v1::Job&)>;
  std::uint64_t subscribe(const std::string& job_id, Listener listener);
  void unsubscribe(std::uint64_t token);

  JobStore& store() { return store_; }
  const std::string& worker_id() const { return worker_id_; }
  // Waits until this runner runs nothing and its last claim found the queue empty (tests);
  // false on timeout.
  bool wait_idle(std::chrono::milliseconds timeout);

 private:
  using Clock = std::chrono::steady_clock;
  enum class Overdue { kNo, kDeadline, kStalled };
  struct Running {
    JobLease lease;
    std::atomic<bool> cancel{false};
    std::atomic<bool> lost{false};
    std::atomic<Overdue> overdue{Overdue::kNo};  // set by the watchdog, honoured by the job
    Clock::time_point started = Clock::now();
    std::atomic<Clock::rep> last_read{Clock::now().time_since_epoch().count()};  // last chunk read
    // The dispatcher's alone: whether a stop was pending at its last heartbeat, and whether it
    // wrote the job's end itself (the job's thread did not respond).
    bool stop_pending = false;
    bool ended_by_watchdog = false;
  };

  void dispatch_loop();
  // Probes the store and reports its health; true when it takes writes.
  bool probe_store();
  void set_store_health(const std::string& problem);
  void renew_leases();
  void reap_expired();
  void watch_running();
  void end_unresponsive(Running& running);
  // Jobs in running_ ended by the watchdog whose threads have not returned. Under mu_, on the
  // dispatcher.
  std::size_t blocked_jobs_locked() const;
  void replace_blocked_thread();
  std::string overdue_message(Overdue overdue) const;
  void claim_more();
  void run(const std::shared_ptr<Running>& running, JobRecord record);
  void run_job(Running& running, JobRecord& record);
  void drop_upload(const JobRecord& record);
  void on_event(const JobEvent& event);
  void publish_stored(const std::string& job_id);
  void publish(const v1::Job& job);

  JobStore& store_;
  Metrics& metrics_;
  const JobRunnerOptions options_;
  const std::string worker_id_;
  std::mutex mu_;
  std::condition_variable wake_cv_;
  std::condition_variable idle_;
  std::map<std::string, std::shared_ptr<Running>> running_;
  bool wake_ = false;         // something to claim may be there
  bool queue_empty_ = false;  // the last claim found nothing
  bool stopping_ = false;
  bool claim_failed_ = false;  // logged once per streak of failures
  std::atomic<bool> stop_flag_{false};
  std::uint64_t next_token_ = 1;
  std::map<std::uint64_t, std::pair<std::string, Listener>> listeners_;
  std::mutex health_mu_;  // orders the health listener's calls
  StoreHealthListener on_store_health_;
  std::string store_problem_;        // "" while the store takes writes
  bool store_health_known_ = false;  // reported at least once
  std::thread dispatcher_;
  WorkerPool pool_;  // last: its threads are joined before anything they use is destroyed
};

}  // namespace posefuse::server
