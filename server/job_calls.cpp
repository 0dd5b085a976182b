#include "server/job_calls.hpp"

#include <deque>
#include <memory>
#include <mutex>

#include "server/job_limits.hpp"
#include "server/status.hpp"

namespace posefuse::server {

namespace {

// Streams messages from a queue, one write at a time; the last one finishes the call. Owned by a
// shared_ptr (self_) until OnDone, so that listeners holding a weak_ptr never see it destroyed.
template <class Message>
class QueuedWriter : public grpc::ServerWriteReactor<Message> {
 public:
  void OnWriteDone(bool ok) override {
    std::lock_guard lock(mu_);
    writing_ = false;
    if (!ok) {
      finish_locked(grpc::Status(grpc::StatusCode::CANCELLED, "stream broken"));
      return;
    }
    next_locked();
  }
  void OnCancel() override {
    std::lock_guard lock(mu_);
    if (!writing_) finish_locked(grpc::Status(grpc::StatusCode::CANCELLED, "cancelled"));
  }
  void OnDone() override {
    std::shared_ptr<QueuedWriter> keep_until_return;
    {
      std::lock_guard lock(mu_);
      keep_until_return = std::move(self_);
    }
    on_done();
  }

 protected:
  virtual void on_done() {}
  // Queues `message`; `last` finishes the call with OK after it.
  void push(Message message, bool last) {
    std::lock_guard lock(mu_);
    if (finished_ || last_queued_) return;
    queue_.push_back(std::move(message));
    last_queued_ = last;
    if (!writing_) next_locked();
  }
  void finish(grpc::Status status) {
    std::lock_guard lock(mu_);
    if (!writing_) finish_locked(std::move(status));
  }

  std::shared_ptr<QueuedWriter> self_;

 private:
  void next_locked() {
    if (finished_) return;
    if (queue_.empty()) {
      if (last_queued_) finish_locked(grpc::Status::OK);
      return;
    }
    buffer_ = std::move(queue_.front());
    queue_.pop_front();
    writing_ = true;
    this->StartWrite(&buffer_);
  }
  void finish_locked(grpc::Status status) {
    if (finished_) return;
    finished_ = true;
    this->Finish(std::move(status));
  }

  std::mutex mu_;
  std::deque<Message> queue_;
  Message buffer_;
  bool writing_ = false;
  bool last_queued_ = false;
  bool finished_ = false;
};

class WatchJob : public QueuedWriter<v1::Job> {
 public:
  WatchJob(JobRunner& runner, std::string job_id) : runner_(runner), job_id_(std::move(job_id)) {}
  void start(const std::shared_ptr<WatchJob>& self, const std::string& tenant) {
    self_ = self;
    // Subscribe before reading the current state, so that no change is missed.
    std::weak_ptr<WatchJob> weak = self;
    token_ = runner_.subscribe(job_id_, [weak](const v1::Job& job) {
      if (auto watcher = weak.lock()) watcher->push_bounded(job);
    });
    std::optional<JobRecord> record;
    try {
      record = runner_.store().get(job_id_);
    } catch (const Error& error) {  // the job store failed
      finish(to_status(error));
      return;
    }
    if (!record || record->owner != tenant) {
      finish(grpc::Status(grpc::StatusCode::NOT_FOUND, "job_id: no job '" + job_id_ + "'"));
      return;
    }
    push_bounded(record->job);
  }

 private:
  // Versions arrive from the store's events and from the first read, possibly twice and, when
  // two reads cross, an older one after a newer: those are skipped (an end never is).
  void push_bounded(v1::Job job) {
    bound_stored_job(job);
    const bool last = is_terminal(job.state());
    {
      std::lock_guard lock(seen_mu_);
      std::string bytes = job.SerializeAsString();
      if (bytes == last_sent_) return;
      if (!last && job.update_time_unix_us() < last_update_time_us_) return;
      last_sent_ = std::move(bytes);
      last_update_time_us_ = job.update_time_unix_us();
    }
    push(std::move(job), last);
  }
  void on_done() override { runner_.unsubscribe(token_); }
  JobRunner& runner_;
  std::string job_id_;
  std::uint64_t token_ = 0;
  std::mutex seen_mu_;
  std::string last_sent_;
  std::int64_t last_update_time_us_ = 0;
};

class JobResults : public QueuedWriter<v1::FitResult> {
 public:
  void start(const std::shared_ptr<JobResults>& self, JobRunner& runner, const std::string& id,
             const std::string& tenant) {
    self_ = self;
    std::optional<JobRecord> record;
    std::vector<v1::FitResult> results;
    try {
      record = runner.store().get(id);
      if (record && record->owner != tenant) record.reset();  // as if it did not exist
      if (record && is_terminal(record->job.state())) results = runner.store().results(id);
    } catch (const Error& error) {  // the job store failed
      finish(to_status(error));
      return;
    }
    if (!record) {
      finish(grpc::Status(grpc::StatusCode::NOT_FOUND, "job_id: no job '" + id + "'"));
      return;
    }
    if (!is_terminal(record->job.state())) {
      finish(grpc::Status(grpc::StatusCode::FAILED_PRECONDITION,
                          "job_id: job '" + id + "' is " + v1::Job::State_Name(record->job.state()) +
                              "; its results are complete when it has finished (WatchJob)"));
      return;
    }
    if (results.empty()) {
      finish(grpc::Status::OK);
      return;
    }
    for (std::size_t i = 0; i < results.size(); ++i) {
      push(std::move(results[i]), i + 1 == results.size());
    }
  }
};

}  // namespace

grpc::ServerWriteReactor<v1::Job>* watch_job(JobRunner& runner, const std::string& job_id, const std::string& tenant) {
  auto watcher = std::make_shared<WatchJob>(runner, job_id);
  watcher->start(watcher, tenant);
  return watcher.get();
}

grpc::ServerWriteReactor<v1::FitResult>* job_results(JobRunner& runner, const std::string& job_id,
                                                     const std::string& tenant) {
  auto writer = std::make_shared<JobResults>();
  writer->start(writer, runner, job_id, tenant);
  return writer.get();
}

}  // namespace posefuse::server
