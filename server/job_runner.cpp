#include "server/job_runner.hpp"

#include <chrono>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "server/job_recording.hpp"
#include "server/log.hpp"
#include "server/status.hpp"
#include "session/pipeline.hpp"
#include "session/stages/default_stages.hpp"

namespace posefuse::server {

namespace {

std::int64_t now_unix_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// A write to the job store that failed (a full disk, an I/O error). A type of its own, not a
// posefuse::Error: the pipeline reports an Error thrown by a stage as an item error and goes
// on, but a job whose results cannot be stored must stop.
class StoreWriteFailed : public std::runtime_error {
 public:
  explicit StoreWriteFailed(const Error& error)
      : std::runtime_error(error.what()), code_(error.code()) {}
  ErrorCode code() const { return code_; }

 private:
  ErrorCode code_;
};

template <class Write>
void store_write(Write&& write) {
  try {
    write();
  } catch (const Error& error) {
    throw StoreWriteFailed(error);
  }
}

// Buffers a job's results and writes them to the store in batches; keeps the job's progress.
class StoreSink : public session::ResultSink {
 public:
  StoreSink(JobStore& store, v1::Job& job, std::function<void(const v1::Job&)> on_progress)
      : store_(store), job_(job), on_progress_(std::move(on_progress)) {}
  void emit(v1::FitResult&& result) override {
    if (result.has_progress()) *job_.mutable_progress() = result.progress();
    if (result.has_summary()) *job_.mutable_summary() = result.summary();
    const bool progress = result.has_progress();
    pending_.push_back(std::move(result));
    if (pending_.size() >= 64 || progress) flush(progress);
  }
  // Throws StoreWriteFailed.
  void flush(bool job_changed) {
    if (!pending_.empty()) store_write([&] { store_.append_results(job_.job_id(), pending_); });
    pending_.clear();
    if (job_changed) {
      job_.set_update_time_unix_us(now_unix_us());
      store_write([&] { store_.update(job_); });
      on_progress_(job_);
    }
  }

 private:
  JobStore& store_;
  v1::Job& job_;
  std::function<void(const v1::Job&)> on_progress_;
  std::vector<v1::FitResult> pending_;
};

void fail_job(v1::Job& job, grpc::StatusCode code, const std::string& message) {
  job.set_state(v1::Job::FAILED);
  job.set_error_code(static_cast<int>(code));
  job.set_error_message(message);
}

// An uploaded recording (no recording_uri) is the server's own spooled copy: once its job has
// finished nothing reads it again. A recording submitted by reference belongs to its owner.
void drop_uploaded_recording(const JobRecord& record) {
  if (!record.job.recording_uri().empty()) return;
  std::error_code ignored;
  std::filesystem::remove(record.recording_path, ignored);
}

}  // namespace

bool is_terminal(v1::Job::State state) {
  return state == v1::Job::SUCCEEDED || state == v1::Job::FAILED || state == v1::Job::CANCELLED;
}

JobRunner::JobRunner(JobStore& store, WorkerPool& pool, Metrics& metrics, unsigned max_running,
                     std::filesystem::path recordings_root)
    : store_(store),
      pool_(pool),
      metrics_(metrics),
      max_running_(std::max(1u, max_running)),
      recordings_root_(std::move(recordings_root)) {}

JobRunner::~JobRunner() {
  std::unique_lock lock(mu_);
  stopping_ = true;
  stop_flag_ = true;
  queue_.clear();
  idle_.wait(lock, [this] { return running_.empty(); });
}

void JobRunner::resume_unfinished() {
  for (JobRecord& record : store_.unfinished()) {
    store_.clear_results(record.job.job_id());
    record.job.set_state(v1::Job::QUEUED);
    record.job.clear_progress();
    record.job.set_update_time_unix_us(now_unix_us());
    store_.update(record.job);
    log_event("info", "job_resumed", {{"job", record.job.job_id()}});
    std::lock_guard lock(mu_);
    queue_.push_back(record.job.job_id());
  }
  std::lock_guard lock(mu_);
  start_next_locked();
}

v1::Job JobRunner::submit(const v1::JobSpec& spec, const std::string& recording_path,
                          const std::string& owner) {
  const v1::Job job = store_.create(spec, recording_path, owner, now_unix_us());
  log_event("info", "job_submitted", {{"job", job.job_id()}});
  std::lock_guard lock(mu_);
  queue_.push_back(job.job_id());
  start_next_locked();
  return job;
}

std::optional<v1::Job> JobRunner::cancel(const std::string& job_id, const std::string& owner) {
  std::optional<JobRecord> record = store_.get(job_id);
  if (!record || record->owner != owner) return std::nullopt;
  if (is_terminal(record->job.state())) return record->job;
  {
    std::lock_guard lock(mu_);
    if (running_.count(job_id)) {
      // The worker stops before its next chunk and stores CANCELLED itself.
      cancel_requested_.insert(job_id);
      return record->job;
    }
    std::erase(queue_, job_id);
  }
  record->job.set_state(v1::Job::CANCELLED);
  record->job.set_update_time_unix_us(now_unix_us());
  store_.update(record->job);
  drop_uploaded_recording(*record);
  publish(record->job);
  return record->job;
}

void JobRunner::start_next_locked() {
  while (!stopping_ && running_.size() < max_running_ && !queue_.empty()) {
    const std::string id = queue_.front();
    queue_.pop_front();
    running_.insert(id);
    pool_.submit([this, id] { run(id); });
  }
}

void JobRunner::run(const std::string& job_id) {
  // Nothing may escape a worker task: an exception there would end the process.
  try {
    std::optional<JobRecord> record = store_.get(job_id);
    if (record && !is_terminal(record->job.state())) run_job(*record);
  } catch (const std::exception&) {
    // Only the store's read of the job can get here (run_job catches what it does itself).
    log_event("error", "job_store_error", {{"job", job_id}});
  }
  std::lock_guard lock(mu_);
  running_.erase(job_id);
  cancel_requested_.erase(job_id);
  start_next_locked();
  idle_.notify_all();
}

void JobRunner::run_job(JobRecord& record) {
  v1::Job& job = record.job;
  const std::string job_id = job.job_id();
  bool handed_back = false;
  // Set when the store refused a write: the job fails with it, whatever the pipeline did.
  std::optional<StoreWriteFailed> store_failure;
  StoreSink sink(store_, job, [this](const v1::Job& j) { publish(j); });
  try {
    job.set_state(v1::Job::RUNNING);
    job.set_update_time_unix_us(now_unix_us());
    store_write([&] { store_.update(job); });
    publish(job);
    auto source = open_job_recording(record, recordings_root_);
    session::PipelineOptions pipeline_options;
    pipeline_options.on_stage_time = [this](std::string_view stage, double seconds) {
      metrics_.stage_time(stage, seconds);
    };
    session::SessionPipeline pipeline(session::make_default_stages(), sink, pipeline_options);
    session::SessionChunk chunk;
    bool cancelled = false;
    while (source->next(chunk)) {
      if (stop_flag_) {
        handed_back = true;
        break;
      }
      {
        std::lock_guard lock(mu_);
        cancelled = cancel_requested_.count(job_id) > 0;
      }
      if (cancelled) break;
      pipeline.push(chunk);
      if (pipeline.ended()) break;
    }
    if (!handed_back && !cancelled) pipeline.close();
    if (!handed_back) job.set_state(cancelled ? v1::Job::CANCELLED : v1::Job::SUCCEEDED);
  } catch (const StoreWriteFailed& failure) {
    store_failure = failure;
  } catch (const Error& error) {
    fail_job(job, status_code(error.code()), error.what());
  } catch (const std::exception& error) {
    fail_job(job, grpc::StatusCode::INTERNAL, std::string("internal error: ") + error.what());
  }
  // The results that came before the end or the error.
  if (!store_failure) {
    try {
      sink.flush(false);
    } catch (const StoreWriteFailed& failure) {
      store_failure = failure;
    }
  }
  if (store_failure) {
    handed_back = false;  // a job that cannot be stored is not resumed by this process either
    fail_job(job, status_code(store_failure->code()),
             std::string("the job store refused a write, the job's results are incomplete: ") +
                 store_failure->what());
    log_event("error", "job_store_write_failed", {{"job", job_id}});
  }
  if (handed_back) return;
  job.set_update_time_unix_us(now_unix_us());
  try {
    store_.update(job);
  } catch (const Error&) {
    // Watchers still learn the end below; the store keeps the job unfinished, so the next
    // start runs it again.
    log_event("error", "job_store_write_failed", {{"job", job_id}});
  }
  drop_uploaded_recording(record);
  publish(job);
  metrics_.job_finished(v1::Job::State_Name(job.state()));
  log_event("info", "job_end", {{"job", job_id}, {"state", v1::Job::State_Name(job.state())}});
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
  return idle_.wait_for(lock, timeout, [this] { return running_.empty() && queue_.empty(); });
}

}  // namespace posefuse::server
