#include "server/job_runner.hpp"

#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "server/job_recording.hpp"
#include "server/job_store_errors.hpp"
#include "server/log.hpp"
#include "server/random_id.hpp"
#include "server/status.hpp"
#include "session/pipeline.hpp"
#include "session/stages/default_stages.hpp"

namespace posefuse::server {

namespace {

std::int64_t now_unix_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// "<host>-<pid>-<random>": readable in the store and in logs, unique across restarts.
std::string make_worker_id() {
  char host[256] = {};
  if (::gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
  return std::string(host[0] ? host : "worker") + "-" + std::to_string(::getpid()) + "-" + random_hex_id().substr(0, 8);
}

// A write to the job store that failed (a full disk, an I/O error). A type of its own, not a
// posefuse::Error: the pipeline reports an Error thrown by a stage as an item error and goes
// on, but a job whose results cannot be stored must stop.
class StoreWriteFailed : public std::runtime_error {
 public:
  explicit StoreWriteFailed(const Error& error) : std::runtime_error(error.what()), code_(error.code()) {}
  ErrorCode code() const { return code_; }

 private:
  ErrorCode code_;
};

// The run must stop without writing anything more: its lease is gone, or the store cannot be
// reached (the lease then expires and another attempt runs the job).
class RunAbandoned : public std::runtime_error {
 public:
  RunAbandoned(const char* reason, bool lease_lost) : std::runtime_error(reason), lease_lost_(lease_lost) {}
  bool lease_lost() const { return lease_lost_; }

 private:
  bool lease_lost_;
};

// The watchdog stopped the run (job_runner.hpp): the job fails with DEADLINE_EXCEEDED.
class RunOverdue : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

template <class Write>
void store_write(Write&& write) {
  try {
    write();
  } catch (const LeaseLost&) {
    throw RunAbandoned("lease_lost", true);
  } catch (const StoreUnavailable&) {
    throw RunAbandoned("job_store_unavailable", false);
  } catch (const Error& error) {
    throw StoreWriteFailed(error);
  }
}

// Buffers a job's results and writes them to the store in batches; keeps the job's progress.
class StoreSink : public session::ResultSink {
 public:
  StoreSink(JobStore& store, const JobLease& lease, v1::Job& job) : store_(store), lease_(lease), job_(job) {}
  void emit(v1::FitResult&& result) override {
    if (result.has_progress()) *job_.mutable_progress() = result.progress();
    if (result.has_summary()) *job_.mutable_summary() = result.summary();
    const bool progress = result.has_progress();
    pending_.push_back(std::move(result));
    if (pending_.size() >= 64 || progress) flush(progress);
  }
  // Throws StoreWriteFailed or RunAbandoned.
  void flush(bool job_changed) {
    if (!pending_.empty()) store_write([&] { store_.append_results(lease_, pending_); });
    pending_.clear();
    if (job_changed) {
      job_.set_update_time_unix_us(now_unix_us());
      store_write([&] { store_.update_running(lease_, job_); });
    }
  }

 private:
  JobStore& store_;
  const JobLease& lease_;
  v1::Job& job_;
  std::vector<v1::FitResult> pending_;
};

void fail_job(v1::Job& job, grpc::StatusCode code, const std::string& message) {
  job.set_state(v1::Job::FAILED);
  job.set_error_code(static_cast<int>(code));
  job.set_error_message(message);
}

}  // namespace

JobRunner::JobRunner(JobStore& store, Metrics& metrics, JobRunnerOptions options)
    : store_(store),
      metrics_(metrics),
      options_([&] {
        options.max_running = std::max(1u, options.max_running);
        return std::move(options);
      }()),
      worker_id_(make_worker_id()),
      pool_(options_.max_running) {
  store_.set_event_listener([this](const JobEvent& event) { on_event(event); });
}

JobRunner::~JobRunner() {
  stop(std::chrono::milliseconds::max());
  store_.set_event_listener({});
}

std::vector<std::string> JobRunner::stop(std::chrono::milliseconds bound) {
  {
    std::lock_guard lock(mu_);
    stopping_ = true;
    stop_flag_ = true;
  }
  wake_cv_.notify_all();
  if (dispatcher_.joinable()) dispatcher_.join();
  std::unique_lock lock(mu_);
  const auto stopped = [this] { return running_.empty(); };
  if (bound == std::chrono::milliseconds::max()) {
    idle_.wait(lock, stopped);
  } else {
    idle_.wait_for(lock, bound, stopped);
  }
  std::vector<std::string> blocked;
  for (const auto& [job_id, running] : running_) blocked.push_back(job_id);
  return blocked;
}

void JobRunner::start(StoreHealthListener on_store_health) {
  {
    std::lock_guard lock(health_mu_);
    on_store_health_ = std::move(on_store_health);
  }
  if (options_.claims_jobs) {
    log_event("info", "job_worker_start",
              {{"worker", worker_id_},
               {"max_jobs", std::to_string(options_.max_running)},
               {"lease_ms", std::to_string(options_.lease.count())}});
  }
  dispatcher_ = std::thread([this] { dispatch_loop(); });
}

std::string JobRunner::store_problem() {
  std::lock_guard lock(health_mu_);
  return store_problem_;
}

bool JobRunner::probe_store() {
  try {
    store_.probe();
    set_store_health("");
    return true;
  } catch (const std::exception& error) {
    set_store_health(error.what());
    return false;
  }
}

void JobRunner::set_store_health(const std::string& problem) {
  std::lock_guard lock(health_mu_);
  const bool changed = !store_health_known_ || problem.empty() != store_problem_.empty();
  store_problem_ = problem;
  store_health_known_ = true;
  if (!changed) return;
  if (problem.empty()) {
    log_event("info", "job_store_serving");
  } else {
    log_event("error", "job_store_not_serving", {{"error", problem}});
  }
  if (on_store_health_) on_store_health_(problem.empty());
}

void JobRunner::dispatch_loop() {
  using Clock = std::chrono::steady_clock;
  Clock::time_point next_heartbeat = Clock::now();
  while (true) {
    {
      std::unique_lock lock(mu_);
      wake_cv_.wait_until(lock, next_heartbeat, [this] { return stopping_ || wake_; });
      if (stopping_) return;
      wake_ = false;
    }
    bool store_serving = store_problem().empty();
    if (Clock::now() >= next_heartbeat) {
      next_heartbeat = Clock::now() + options_.heartbeat;
      store_serving = probe_store();
      if (options_.claims_jobs) {
        // Renewed even while the store fails: a lease that expired would make this worker's
        // running jobs start over once it works again.
        renew_leases();
        watch_running();
        if (store_serving) reap_expired();
      }
    }
    // Nothing is claimed while the store refuses writes: a claimed job could only fail.
    if (options_.claims_jobs && store_serving) {
      claim_more();
    } else {
      std::lock_guard lock(mu_);
      queue_empty_ = true;  // nothing this runner can take up now (wait_idle)
      idle_.notify_all();
    }
  }
}

void JobRunner::renew_leases() {
  std::vector<std::shared_ptr<Running>> running;
  {
    std::lock_guard lock(mu_);
    for (const auto& [id, entry] : running_) running.push_back(entry);
  }
  for (const auto& entry : running) {
    try {
      switch (store_.renew(entry->lease, options_.lease)) {
        case LeaseState::kHeld: break;
        case LeaseState::kCancelRequested: entry->cancel = true; break;
        case LeaseState::kLost: entry->lost = true; break;
      }
    } catch (const std::exception& error) {
      // The job goes on; if the store stays away past the lease, another attempt takes over.
      log_event("warning", "job_lease_renew_failed", {{"job", entry->lease.job_id}, {"error", error.what()}});
    }
  }
}

void JobRunner::watch_running() {
  std::vector<std::shared_ptr<Running>> running;
  {
    std::lock_guard lock(mu_);
    for (const auto& [id, entry] : running_) running.push_back(entry);
  }
  const Clock::time_point now = Clock::now();
  for (const auto& entry : running) {
    if (entry->ended_by_watchdog) continue;
    if (entry->overdue == Overdue::kNo) {
      const Clock::time_point last_read{Clock::duration(entry->last_read.load())};
      if (options_.deadline.count() > 0 && now - entry->started >= options_.deadline) {
        entry->overdue = Overdue::kDeadline;
      } else if (options_.stall.count() > 0 && now - last_read >= options_.stall) {
        entry->overdue = Overdue::kStalled;
      }
    }
    const bool must_stop = entry->cancel || entry->overdue != Overdue::kNo;
    // A heartbeat is far longer than a chunk takes: a stop still pending one heartbeat after it
    // was seen is one the job's thread cannot get to.
    if (must_stop && entry->stop_pending) end_unresponsive(*entry);
    entry->stop_pending = must_stop;
  }
}

void JobRunner::end_unresponsive(Running& running) {
  const std::string& job_id = running.lease.job_id;
  try {
    const std::optional<JobRecord> record = store_.get(job_id);
    if (!record || record->job.state() != v1::Job::RUNNING) return;
    v1::Job job = record->job;
    const Overdue overdue = running.overdue;
    if (overdue != Overdue::kNo) {
      fail_job(job, grpc::StatusCode::DEADLINE_EXCEEDED, overdue_message(overdue));
    } else {
      job.set_state(v1::Job::CANCELLED);
    }
    job.set_update_time_unix_us(now_unix_us());
    store_.update_running(running.lease, job);  // a terminal state: the lease ends with it
    running.ended_by_watchdog = true;
    replace_blocked_thread();
    drop_upload(*record);
    metrics_.job_finished(record->owner, v1::Job::State_Name(job.state()));
    log_event("warning", "job_ended_unresponsive", {{"job", job_id}, {"state", v1::Job::State_Name(job.state())}});
  } catch (const LeaseLost&) {
    running.ended_by_watchdog = true;  // it ended meanwhile, or another attempt holds it
  } catch (const std::exception& error) {
    // Tried again at the next heartbeat; should the store stay away, the lease expires.
    log_event("warning", "job_end_unresponsive_failed", {{"job", job_id}, {"error", error.what()}});
  }
}

std::size_t JobRunner::blocked_jobs_locked() const {
  std::size_t blocked = 0;
  for (const auto& [id, entry] : running_) blocked += entry->ended_by_watchdog ? 1 : 0;
  return blocked;
}

void JobRunner::replace_blocked_thread() {
  // The ended job's thread is still blocked inside its read, holding a pool thread: one more
  // thread takes its place so that later jobs do not wait behind it. At most max_running
  // spares however many block: past that the reads themselves are what is wrong.
  std::size_t blocked = 0;
  {
    std::lock_guard lock(mu_);
    blocked = blocked_jobs_locked();
  }
  if (blocked > options_.max_running || pool_.threads() >= options_.max_running + blocked) return;
  pool_.add_thread();
  log_event("warning", "job_thread_replaced", {{"blocked_jobs", std::to_string(blocked)}});
}

std::string JobRunner::overdue_message(Overdue overdue) const {
  const auto seconds = [](std::chrono::milliseconds limit) {
    std::ostringstream text;
    text << limit.count() / 1000.0;
    return text.str();
  };
  if (overdue == Overdue::kDeadline) {
    return "job: ran for longer than --job-deadline-s (" + seconds(options_.deadline) + " s) and was stopped";
  }
  return "job: read no chunk of its recording for --job-stall-s (" + seconds(options_.stall) + " s) and was stopped";
}

void JobRunner::reap_expired() {
  try {
    for (const ReapedJob& job : store_.reap(options_.max_attempts, now_unix_us())) {
      log_event("info", "job_lease_expired", {{"job", job.job_id}, {"state", v1::Job::State_Name(job.state)}});
      if (job.state == v1::Job::QUEUED) continue;
      const std::optional<JobRecord> record = store_.get(job.job_id);
      metrics_.job_finished(record ? record->owner : "", v1::Job::State_Name(job.state));
      // Finished without its worker: nothing reads its upload again.
      if (record) drop_upload(*record);
    }
  } catch (const std::exception& error) {
    log_event("warning", "job_reap_failed", {{"error", error.what()}});
  }
}

void JobRunner::claim_more() {
  while (true) {
    {
      std::lock_guard lock(mu_);
      // A job ended by the watchdog whose thread is still blocked takes no slot.
      if (stopping_ || running_.size() - blocked_jobs_locked() >= options_.max_running) return;
    }
    std::optional<JobRecord> record;
    try {
      record = store_.claim(worker_id_, options_.lease, now_unix_us());
      if (claim_failed_) log_event("info", "job_claim_recovered");
      claim_failed_ = false;
    } catch (const std::exception& error) {
      if (!claim_failed_) log_event("error", "job_claim_failed", {{"error", error.what()}});
      claim_failed_ = true;
    }
    std::lock_guard lock(mu_);
    if (!record) {
      queue_empty_ = true;
      idle_.notify_all();
      return;
    }
    queue_empty_ = false;
    auto running = std::make_shared<Running>();
    running->lease = {record->job.job_id(), worker_id_, record->attempts};
    running_[record->job.job_id()] = running;
    log_event("info", "job_claimed",
              {{"job", record->job.job_id()}, {"attempt", std::to_string(record->attempts)}, {"worker", worker_id_}});
    pool_.submit([this, running, record = std::move(*record)]() mutable { run(running, std::move(record)); });
  }
}

v1::Job JobRunner::submit(const v1::JobSpec& spec, const std::string& recording_path, const std::string& owner) {
  const v1::Job job = store_.create(spec, recording_path, owner, now_unix_us());
  log_event("info", "job_submitted", {{"job", job.job_id()}});
  {
    std::lock_guard lock(mu_);
    wake_ = true;
  }
  wake_cv_.notify_all();
  return job;
}

std::optional<v1::Job> JobRunner::cancel(const std::string& job_id, const std::string& owner) {
  const std::optional<JobRecord> record = store_.cancel(job_id, owner, now_unix_us());
  if (!record) return std::nullopt;
  if (record->job.state() == v1::Job::CANCELLED) drop_upload(*record);
  return record->job;
}

void JobRunner::drop_upload(const JobRecord& record) {
  // A recording submitted by reference belongs to its owner; only uploads are ours.
  if (!record.job.recording_uri().empty()) return;
  try {
    store_.drop_upload(record.recording_path, options_.scratch_dir);
  } catch (const std::exception& error) {
    log_event("warning", "upload_drop_failed", {{"job", record.job.job_id()}, {"error", error.what()}});
  }
}

void JobRunner::run(const std::shared_ptr<Running>& running, JobRecord record) {
  // Nothing may escape a worker task: an exception there would end the process.
  try {
    run_job(*running, record);
  } catch (const std::exception& error) {
    log_event("error", "job_runner_error", {{"job", record.job.job_id()}, {"error", error.what()}});
  }
  // Everything under the lock: once running_ is empty the destructor may free this runner.
  std::lock_guard lock(mu_);
  running_.erase(record.job.job_id());
  wake_ = true;
  idle_.notify_all();
  wake_cv_.notify_all();
}

void JobRunner::run_job(Running& running, JobRecord& record) {
  v1::Job& job = record.job;
  const std::string job_id = job.job_id();
  const JobLease& lease = running.lease;
  bool handed_back = false;
  std::optional<RunAbandoned> abandoned;
  // Set when the store refused a write: the job fails with it, whatever the pipeline did.
  std::optional<StoreWriteFailed> store_failure;
  StoreSink sink(store_, lease, job);
  try {
    JobRecord local = record;
    if (job.recording_uri().empty()) {
      try {
        local.recording_path = store_.local_recording(record.recording_path, options_.scratch_dir);
      } catch (const StoreUnavailable&) {
        throw RunAbandoned("job_store_unavailable", false);
      }
    }
    auto source = open_job_recording(local, options_.recordings_root);
    session::PipelineOptions pipeline_options;
    pipeline_options.max_held_bytes = options_.max_held_bytes;
    pipeline_options.max_held_bytes_setting = "--max-session-memory-mb";
    pipeline_options.on_stage_time = [this](std::string_view stage, double seconds) {
      metrics_.stage_time(stage, seconds);
    };
    session::SessionPipeline pipeline(session::make_default_stages(), sink, pipeline_options);
    session::SessionChunk chunk;
    bool cancelled = false;
    while (source->next(chunk)) {
      running.last_read = Clock::now().time_since_epoch().count();
      if (stop_flag_) {
        handed_back = true;
        break;
      }
      if (running.lost) throw RunAbandoned("lease_lost", true);
      // The deadline is checked here too, so that it holds to the chunk, not to the heartbeat.
      if (options_.deadline.count() > 0 && Clock::now() - running.started >= options_.deadline) {
        running.overdue = Overdue::kDeadline;
      }
      if (const Overdue overdue = running.overdue; overdue != Overdue::kNo) throw RunOverdue(overdue_message(overdue));
      cancelled = running.cancel;
      if (cancelled) break;
      pipeline.push(chunk);
      if (pipeline.ended()) break;
    }
    if (!handed_back && !cancelled) pipeline.close();
    if (!handed_back) job.set_state(cancelled ? v1::Job::CANCELLED : v1::Job::SUCCEEDED);
  } catch (const RunAbandoned& reason) {
    abandoned = reason;
  } catch (const StoreWriteFailed& failure) {
    store_failure = failure;
  } catch (const RunOverdue& overdue) {
    fail_job(job, grpc::StatusCode::DEADLINE_EXCEEDED, overdue.what());
  } catch (const Error& error) {
    fail_job(job, status_code(error.code()), error.what());
  } catch (const std::exception& error) {
    fail_job(job, grpc::StatusCode::INTERNAL, std::string("internal error: ") + error.what());
  }
  // The results that came before the end or the error.
  if (!store_failure && !abandoned && !handed_back) {
    try {
      sink.flush(false);
    } catch (const StoreWriteFailed& failure) {
      store_failure = failure;
    } catch (const RunAbandoned& reason) {
      abandoned = reason;
    }
  }
  if (abandoned) {
    log_event("warning", "job_abandoned", {{"job", job_id}, {"reason", abandoned->what()}});
    if (!abandoned->lease_lost()) set_store_health("job_store: unavailable while job '" + job_id + "' was running");
    if (!abandoned->lease_lost()) handed_back = true;  // try to give it back at once
  }
  if (handed_back) {
    try {
      store_.release(lease, now_unix_us());
      log_event("info", "job_handed_back", {{"job", job_id}});
    } catch (const std::exception&) {
      // The lease expires instead; a worker then takes the job up again.
    }
    return;
  }
  if (abandoned) return;
  if (store_failure) {
    fail_job(job, status_code(store_failure->code()),
             std::string("the job store refused a write, the job's results are incomplete: ") + store_failure->what());
    log_event("error", "job_store_write_failed", {{"job", job_id}});
    set_store_health(store_failure->what());
  }
  job.set_update_time_unix_us(now_unix_us());
  try {
    store_.update_running(lease, job);
  } catch (const LeaseLost&) {
    log_event("warning", "job_abandoned", {{"job", job_id}, {"reason", "lease_lost"}});
    return;
  } catch (const StoreUnavailable&) {
    // Not stored: the lease expires and another attempt runs the job; watchers learn from it.
    log_event("warning", "job_abandoned", {{"job", job_id}, {"reason", "job_store_unavailable"}});
    return;
  } catch (const Error&) {
    // Watchers here still learn the end; the store keeps the job RUNNING until its lease
    // expires, and then it runs again.
    log_event("error", "job_store_write_failed", {{"job", job_id}});
    publish(job);
  }
  drop_upload(record);
  metrics_.job_finished(record.owner, v1::Job::State_Name(job.state()));
  log_event("info", "job_end",
            {{"job", job_id}, {"state", v1::Job::State_Name(job.state())}, {"attempt", std::to_string(lease.attempt)}});
}

void JobRunner::on_event(const JobEvent& event) {
  switch (event.kind) {
    case JobEvent::Kind::kQueued: {
      {
        std::lock_guard lock(mu_);
        wake_ = true;
      }
      wake_cv_.notify_all();
      return;
    }
    case JobEvent::Kind::kChanged: publish_stored(event.job_id); return;
    case JobEvent::Kind::kCancelRequested: {
      std::lock_guard lock(mu_);
      if (const auto it = running_.find(event.job_id); it != running_.end()) it->second->cancel = true;
      return;
    }
    case JobEvent::Kind::kMissedEvents: {
      std::set<std::string> watched;
      {
        std::lock_guard lock(mu_);
        for (const auto& [token, entry] : listeners_) watched.insert(entry.first);
        wake_ = true;
      }
      wake_cv_.notify_all();
      for (const std::string& id : watched) publish_stored(id);
      return;
    }
  }
}

void JobRunner::publish_stored(const std::string& job_id) {
  {
    std::lock_guard lock(mu_);
    bool watched = false;
    for (const auto& [token, entry] : listeners_) watched = watched || entry.first == job_id;
    if (!watched) return;
  }
  try {
    if (const std::optional<JobRecord> record = store_.get(job_id)) publish(record->job);
  } catch (const std::exception& error) {
    log_event("warning", "job_watch_read_failed", {{"job", job_id}, {"error", error.what()}});
  }
}

std::uint64_t JobRunner::subscribe(const std::string& job_id, Listener listener) {
  std::lock_guard lock(mu_);
  const std::uint64_t token = next_token_++;
  listeners_[token] = {job_id, std::move(listener)};
  return token;
}

void JobRunner::unsubscribe(std::uint64_t token) {
  std::lock_guard lock(mu_);
  listeners_.erase(token);
}

void JobRunner::publish(const v1::Job& job) {
  // Called outside the lock, so that a listener may unsubscribe (listeners keep what they
  // touch alive themselves).
  std::vector<Listener> listeners;
  {
    std::lock_guard lock(mu_);
    for (const auto& [token, entry] : listeners_) {
      if (entry.first == job.job_id()) listeners.push_back(entry.second);
    }
  }
  for (const Listener& listener : listeners) listener(job);
}

bool JobRunner::wait_idle(std::chrono::milliseconds timeout) {
  std::unique_lock lock(mu_);
  return idle_.wait_for(lock, timeout,
                        [this] { return running_.empty() && (!options_.claims_jobs || (queue_empty_ && !wake_)); });
}

}  // namespace posefuse::server
