#include "server/job_calls.hpp"

#include <deque>
#include <iterator>
#include <memory>
#include <mutex>
#include <vector>

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

// A finished job's results, read from the store page by page (kResultsPageSize): the next page
// is read when the last result of the one before has been written.
class JobResults : public grpc::ServerWriteReactor<v1::FitResult> {
 public:
  JobResults(JobRunner& runner, std::string job_id) : runner_(runner), job_id_(std::move(job_id)) {}

  void start(const std::string& tenant) {
    std::optional<JobRecord> record;
    try {
      record = runner_.store().get(job_id_);
    } catch (const Error& error) {  // the job store failed
      Finish(to_status(error));
      return;
    }
    if (!record || record->owner != tenant) {  // another tenant's job: as if it did not exist
      Finish(grpc::Status(grpc::StatusCode::NOT_FOUND, "job_id: no job '" + job_id_ + "'"));
      return;
    }
    if (!is_terminal(record->job.state())) {
      Finish(grpc::Status(grpc::StatusCode::FAILED_PRECONDITION,
                          "job_id: job '" + job_id_ + "' is " + v1::Job::State_Name(record->job.state()) +
                              "; its results are complete when it has finished (WatchJob)"));
      return;
    }
    write_next();
  }

  void OnWriteDone(bool ok) override {
    if (!ok) {
      Finish(grpc::Status(grpc::StatusCode::CANCELLED, "stream broken"));
      return;
    }
    write_next();
  }
  void OnDone() override { delete this; }

 private:
  // One write is in flight at a time, so this runs on one thread at a time.
  void write_next() {
    if (page_.empty() && !last_page_read_) {
      try {
        std::vector<v1::FitResult> page = runner_.store().results(job_id_, next_, kResultsPageSize);
        last_page_read_ = page.size() < kResultsPageSize;
        next_ += page.size();
        page_.assign(std::make_move_iterator(page.begin()), std::make_move_iterator(page.end()));
      } catch (const Error& error) {  // the job store failed: the client sees the results were cut
        Finish(to_status(error));
        return;
      }
    }
    if (page_.empty()) {
      Finish(grpc::Status::OK);
      return;
    }
    buffer_ = std::move(page_.front());
    page_.pop_front();
    StartWrite(&buffer_);
  }

  JobRunner& runner_;
  const std::string job_id_;
  std::deque<v1::FitResult> page_;
  v1::FitResult buffer_;
  std::uint64_t next_ = 0;  // the index of the next result to read
  bool last_page_read_ = false;
};

}  // namespace

grpc::ServerWriteReactor<v1::Job>* watch_job(JobRunner& runner, const std::string& job_id, const std::string& tenant) {
  auto watcher = std::make_shared<WatchJob>(runner, job_id);
  watcher->start(watcher, tenant);
  return watcher.get();
}

grpc::ServerWriteReactor<v1::FitResult>* job_results(JobRunner& runner, const std::string& job_id,
                                                     const std::string& tenant) {
  auto* writer = new JobResults(runner, job_id);  // deletes itself in OnDone
  writer->start(tenant);
  return writer;
}

}  // namespace posefuse::server
