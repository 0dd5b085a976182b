#include "server/job_calls.hpp"

#include <atomic>
#include <deque>
#include <memory>
#include <mutex>

#include "server/log.hpp"
#include "server/random_id.hpp"
#include "server/status.hpp"
#include "server/upload_spool.hpp"
#include "session/pipeline.hpp"

namespace posefuse::server {

namespace {

namespace fs = std::filesystem;

// Reads the JobSpec; by reference, answers with the stored job at once. By upload, each chunk
// read goes to the UploadSpool on the worker pool (validation decodes images: never on a reactor
// thread), and only then is the next one read, so at most one chunk is held and a fast client
// is slowed by flow control; the whole session spooled, the job is stored and returned.
class SubmitJob : public grpc::ServerReadReactor<v1::SubmitJobRequest> {
 public:
  SubmitJob(const SubmitJobContext& context, v1::Job* response)
      : context_(context), response_(response) {
    StartRead(&request_);
  }
  void OnReadDone(bool ok) override {
    if (!spool_) {
      read_spec(ok);
      return;
    }
    // Past the spec: the worker adds the chunk (or commits at the end) and reads on.
    context_.pool.submit([this, ok] { ok ? add_chunk() : commit(); });
  }
  void OnCancel() override { cancelled_ = true; }
  void OnDone() override { delete this; }

 private:
  void read_spec(bool ok) {
    if (!ok || !request_.has_spec()) {
      Finish(grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                          "spec: the first SubmitJobRequest must be a JobSpec"));
      return;
    }
    spec_ = request_.spec();
    try {
      if (spec_.source_case() == v1::JobSpec::kRecordingUri) {
        const fs::path path = resolve_recording(spec_.recording_uri(), context_.recordings_root);
        *response_ = context_.runner.submit(spec_, path.string());
        Finish(grpc::Status::OK);
        return;
      }
      if (!spec_.upload()) {
        throw_invalid("spec.source", "neither recording_uri nor upload is set");
      }
      spool_ = std::make_unique<UploadSpool>(
          context_.spool_dir / (random_hex_id() + ".pfchunks"), context_.max_upload_bytes,
          session::PipelineOptions{}.max_item_errors);
      log_event("info", "upload_start", {});
    } catch (const Error& error) {
      Finish(to_status(error));
      return;
    }
    StartRead(&request_);
  }

  void add_chunk() {
    try {
      if (!request_.has_chunk()) {
        throw_invalid("chunk[" + std::to_string(spool_->chunks()) + "]",
                      "after the JobSpec an upload holds only SessionChunk messages");
      }
      spool_->add(request_.chunk());
    } catch (const Error& error) {
      end_upload(to_status(error));
      return;
    }
    request_.Clear();
    StartRead(&request_);  // last: OnReadDone may run at once on another thread
  }

  void commit() {
    if (cancelled_) {
      end_upload(grpc::Status(grpc::StatusCode::CANCELLED, "upload cancelled"));
      return;
    }
    try {
      const fs::path& path = spool_->commit();
      *response_ = context_.runner.submit(spec_, path.string());
    } catch (const Error& error) {
      end_upload(to_status(error));
      return;
    }
    log_event("info", "upload_end", {{"job", response_->job_id()},
                                      {"chunks", std::to_string(spool_->chunks())},
                                      {"bytes", std::to_string(spool_->bytes())}});
    Finish(grpc::Status::OK);
  }

  // A refused upload leaves nothing: the partial file goes now, not when the call is done.
  void end_upload(grpc::Status status) {
    log_event("info", "upload_refused", {{"code", std::to_string(status.error_code())},
                                         {"chunks", std::to_string(spool_->chunks())}});
    spool_.reset();
    Finish(std::move(status));
  }

  const SubmitJobContext& context_;
  v1::Job* response_;
  v1::SubmitJobRequest request_;
  v1::JobSpec spec_;
  std::unique_ptr<UploadSpool> spool_;
  std::atomic<bool> cancelled_{false};
};

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
  void start(const std::shared_ptr<WatchJob>& self) {
    self_ = self;
    // Subscribe before reading the current state, so that no change is missed.
    std::weak_ptr<WatchJob> weak = self;
    token_ = runner_.subscribe(job_id_, [weak](const v1::Job& job) {
      if (auto watcher = weak.lock()) watcher->push(job, is_terminal(job.state()));
    });
    const auto record = runner_.store().get(job_id_);
    if (!record) {
      finish(grpc::Status(grpc::StatusCode::NOT_FOUND, "job_id: no job '" + job_id_ + "'"));
      return;
    }
    push(record->job, is_terminal(record->job.state()));
  }

 private:
  void on_done() override { runner_.unsubscribe(token_); }
  JobRunner& runner_;
  std::string job_id_;
  std::uint64_t token_ = 0;
};

class JobResults : public QueuedWriter<v1::FitResult> {
 public:
  void start(const std::shared_ptr<JobResults>& self, JobRunner& runner, const std::string& id) {
    self_ = self;
    const auto record = runner.store().get(id);
    if (!record) {
      finish(grpc::Status(grpc::StatusCode::NOT_FOUND, "job_id: no job '" + id + "'"));
      return;
    }
    if (!is_terminal(record->job.state())) {
      finish(grpc::Status(grpc::StatusCode::FAILED_PRECONDITION,
                          "job_id: job '" + id + "' is " +
                              v1::Job::State_Name(record->job.state()) +
                              "; its results are complete when it has finished (WatchJob)"));
      return;
    }
    std::vector<v1::FitResult> results = runner.store().results(id);
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

fs::path resolve_recording(const std::string& uri, const fs::path& root) {
  if (root.empty()) {
    throw Error(ErrorCode::kFailedPrecondition, "spec.recording_uri",
                "the server was started without --recordings-root; submit by reference is off");
  }
  std::string path = uri;
  if (path.rfind("file://", 0) == 0) path = path.substr(7);
  if (path.empty()) throw_invalid("spec.recording_uri", "is empty");
  const fs::path canonical_root = fs::weakly_canonical(root);
  const fs::path resolved = fs::weakly_canonical(canonical_root / fs::path(path).relative_path());
  const auto [root_end, unused] =
      std::mismatch(canonical_root.begin(), canonical_root.end(), resolved.begin(), resolved.end());
  if (root_end != canonical_root.end()) {
    throw_invalid("spec.recording_uri", "'" + uri + "' is outside the server's recordings root");
  }
  if (!fs::exists(resolved)) {
    throw Error(ErrorCode::kNotFound, "spec.recording_uri", "'" + uri + "' does not exist");
  }
  return resolved;
}

grpc::ServerReadReactor<v1::SubmitJobRequest>* submit_job(const SubmitJobContext& context,
                                                          v1::Job* response) {
  return new SubmitJob(context, response);
}

grpc::ServerWriteReactor<v1::Job>* watch_job(JobRunner& runner, const std::string& job_id) {
  auto watcher = std::make_shared<WatchJob>(runner, job_id);
  watcher->start(watcher);
  return watcher.get();
}

grpc::ServerWriteReactor<v1::FitResult>* job_results(JobRunner& runner,
                                                     const std::string& job_id) {
  auto writer = std::make_shared<JobResults>();
  writer->start(writer, runner, job_id);
  return writer.get();
}

}  // namespace posefuse::server
