#include "server/fit_session.hpp"

#include "server/log.hpp"
#include "server/session_memory.hpp"
#include "server/status.hpp"
#include "server/stream_rate.hpp"
#include "session/stages/default_stages.hpp"

namespace posefuse::server {

// The pipeline's results go straight to the session's send queue.
class FitSession::Sink : public session::ResultSink {
 public:
  explicit Sink(FitSession& session) : session_(session) {}
  void emit(v1::FitResult&& result) override { session_.enqueue_result(std::move(result)); }

 private:
  FitSession& session_;
};

FitSession* FitSession::start(grpc::CallbackServerContext* context, std::uint64_t id, std::string tenant,
                              const ServerOptions& options, WorkerPool& pool, SessionRegistry& registry,
                              Metrics& metrics) {
  auto session = std::make_shared<FitSession>(context, id, std::move(tenant), options, pool, registry, metrics);
  session->self_ = session;
  session->sink_ = std::make_unique<Sink>(*session);
  session::PipelineOptions pipeline_options;
  pipeline_options.max_held_bytes = session_memory_bytes(options);
  pipeline_options.max_held_bytes_setting = "--max-session-memory-mb";
  pipeline_options.queued_chunk_bytes = [owner = session.get()] { return owner->inbox_bytes_.load(); };
  pipeline_options.on_stage_time = [&metrics](std::string_view stage, double seconds) {
    metrics.stage_time(stage, seconds);
  };
  session->pipeline_ =
      std::make_unique<session::SessionPipeline>(session::make_default_stages(), *session->sink_, pipeline_options);
  metrics.session_started(session->tenant_);
  registry.watch(id, session);
  log_event("info", "session_start", {{"session", std::to_string(id)}, {"peer", context->peer()}});
  std::lock_guard lock(session->mu_);
  session->start_read_locked();
  return session.get();
}

FitSession::FitSession(grpc::CallbackServerContext* context, std::uint64_t id, std::string tenant,
                       const ServerOptions& options, WorkerPool& pool, SessionRegistry& registry, Metrics& metrics)
    : context_(context),
      id_(id),
      tenant_(std::move(tenant)),
      options_(options),
      pool_(pool),
      registry_(registry),
      metrics_(metrics) {}

void FitSession::clear_inbox_locked() {
  metrics_.queued_chunks_add(-static_cast<std::int64_t>(inbox_.size()));
  inbox_.clear();
  inbox_bytes_ = 0;
}

void FitSession::start_read_locked() {
  read_pending_ = true;
  StartRead(&read_buffer_);
}

void FitSession::OnReadDone(bool ok) {
  std::lock_guard lock(mu_);
  read_pending_ = false;
  if (finished_ || final_status_) return;
  last_read_at_ = Clock::now();
  if (!ok) {
    input_closed_ = true;
  } else {
    ++chunks_read_;
    metrics_.chunk_received(tenant_);
    metrics_.queued_chunks_add(1);
    inbox_bytes_ += read_buffer_.ByteSizeLong();
    inbox_.push_back(std::move(read_buffer_));
    read_buffer_.Clear();
    if (inbox_.size() < options_.max_queued_chunks) start_read_locked();
  }
  schedule_locked();
}

void FitSession::schedule_locked() {
  if (worker_scheduled_ || finished_) return;
  worker_scheduled_ = true;
  worker_scheduled_at_ = Clock::now();
  pool_.submit([self = shared_from_this()] { self->work(); });
}

void FitSession::work() {
  for (;;) {
    v1::SessionChunk chunk;
    bool input_ended = false;
    {
      std::lock_guard lock(mu_);
      stream_time_us_ = pipeline_->stream_time_us();
      if (finished_ || final_status_) {
        worker_returns_locked();
        return;
      }
      if (outbox_.size() >= options_.max_queued_results) {
        worker_waits_for_writes_ = true;
        worker_returns_locked();
        return;
      }
      if (!inbox_.empty()) {
        chunk = std::move(inbox_.front());
        inbox_.pop_front();
        inbox_bytes_ -= chunk.ByteSizeLong();
        metrics_.queued_chunks_add(-1);
        if (!read_pending_ && !input_closed_ && inbox_.size() < options_.max_queued_chunks) {
          start_read_locked();
        }
      } else if (input_closed_) {
        input_ended = true;
      } else {
        worker_returns_locked();
        return;
      }
    }

    std::optional<grpc::Status> status;
    try {
      if (input_ended) {
        pipeline_->close();  // throws: the end marker never came
      } else {
        pipeline_->push(chunk);
      }
      if (pipeline_->ended()) status = grpc::Status::OK;
    } catch (const Error& error) {
      if (input_ended) {
        // The input also ends so when the client goes away: OnDone tells which it was.
        std::lock_guard lock(mu_);
        unended_input_error_ = SessionError{error_code_name(error.code()), error.field()};
      } else {
        log_session_error(error_code_name(error.code()), error.field());
      }
      status = to_status(error);
    } catch (const std::exception& error) {
      log_event("error", "session_internal_error", {{"session", std::to_string(id_)}});
      status = grpc::Status(grpc::StatusCode::INTERNAL, std::string("internal error: ") + error.what());
    }
    if (status) {
      std::lock_guard lock(mu_);
      stream_time_us_ = pipeline_->stream_time_us();
      worker_returns_locked();
      finish_after_writes_locked(std::move(*status));
      return;
    }
  }
}

void FitSession::worker_returns_locked() {
  worker_scheduled_ = false;
  server_busy_ += Clock::now() - worker_scheduled_at_;
}

void FitSession::enqueue_result(v1::FitResult&& result) {
  std::lock_guard lock(mu_);
  if (finished_ || final_status_) return;
  if (result.has_item_error()) {
    ++item_errors_;
    metrics_.item_error(tenant_);
  }
  outbox_.push_back(std::move(result));
  if (!write_pending_) start_write_locked();
}

void FitSession::start_write_locked() {
  write_buffer_ = std::move(outbox_.front());
  outbox_.pop_front();
  write_pending_ = true;
  StartWrite(&write_buffer_);
}

void FitSession::OnWriteDone(bool ok) {
  std::lock_guard lock(mu_);
  write_pending_ = false;
  last_read_at_ = Clock::now();  // the client is alive: it is receiving
  if (!ok) {
    // The client is gone or stopped the stream; nothing more can be sent.
    outbox_.clear();
    if (!final_status_) final_status_ = grpc::Status(grpc::StatusCode::CANCELLED, "stream broken");
    finish_now_locked(*final_status_);
    return;
  }
  if (!outbox_.empty() && !finished_) {
    start_write_locked();
  } else if (final_status_) {
    finish_now_locked(*final_status_);
    return;
  }
  if (worker_waits_for_writes_ && outbox_.size() < options_.max_queued_results / 2 + 1) {
    worker_waits_for_writes_ = false;
    schedule_locked();
  }
}

void FitSession::finish_after_writes_locked(grpc::Status status) {
  if (final_status_) return;
  final_status_ = std::move(status);
  clear_inbox_locked();
  if (!write_pending_ && outbox_.empty()) finish_now_locked(*final_status_);
}

void FitSession::log_session_error(const std::string& code, const std::string& field) const {
  log_event("info", "session_error", {{"session", std::to_string(id_)}, {"code", code}, {"field", field}});
}

void FitSession::finish_now_locked(grpc::Status status) {
  if (finished_) return;
  finished_ = true;
  finished_with_ = status.error_code();
  Finish(std::move(status));
}

void FitSession::OnCancel() {
  std::lock_guard lock(mu_);
  // Cancelled work stops: queued chunks and results are dropped, the worker sees
  // final_status_ before its next chunk.
  clear_inbox_locked();
  outbox_.clear();
  if (!final_status_) final_status_ = grpc::Status(grpc::StatusCode::CANCELLED, "cancelled");
  if (!write_pending_) finish_now_locked(*final_status_);
}

void FitSession::check_idle(Clock::time_point now) {
  std::lock_guard lock(mu_);
  if (finished_) return;
  const bool idle_for_timeout = now - last_read_at_ >= std::chrono::duration<double>(options_.idle_timeout_s);
  if (final_status_) {
    // Decided, but the results before the status are still going out: a client that stopped
    // taking them must not keep the slot either.
    if (write_pending_ && idle_for_timeout) {
      cancelled_by_server_ = true;
      context_->TryCancel();
    }
    return;
  }
  const bool waiting_for_client = (read_pending_ && inbox_.empty() && !worker_scheduled_) || write_pending_;
  if (!waiting_for_client) return;
  if (!idle_for_timeout) {
    check_stream_rate_locked(now);
    return;
  }
  log_event("info", "session_idle", {{"session", std::to_string(id_)}});
  final_status_ =
      grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED,
                   "no message from the client for " + std::to_string(options_.idle_timeout_s) + " s (idle timeout)");
  clear_inbox_locked();
  outbox_.clear();
  if (write_pending_) {
    cancelled_by_server_ = true;
    context_->TryCancel();  // the pending write fails; OnWriteDone finishes the call
  } else {
    finish_now_locked(*final_status_);
  }
}

void FitSession::check_stream_rate_locked(Clock::time_point now) {
  // Judged only once every chunk read has been processed, so that stream_time_us_ is what the
  // client has delivered and the server's busy time is all counted.
  if (worker_scheduled_ || !inbox_.empty()) return;
  const StreamRateRule rule{options_.min_stream_rate, options_.stream_rate_grace_s};
  const double client_s = std::chrono::duration<double>(now - started_at_ - server_busy_).count();
  const auto shortfall = stream_rate_shortfall(rule, client_s, static_cast<double>(stream_time_us_) * 1e-6);
  if (!shortfall) return;
  log_event("info", "session_too_slow",
            {{"session", std::to_string(id_)},
             {"rate", std::to_string(shortfall->rate)},
             {"required_rate", std::to_string(shortfall->required_rate)}});
  // Like the end of the stream: the results of every chunk processed go out first.
  finish_after_writes_locked(grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED, describe(*shortfall, rule)));
}

void FitSession::OnDone() {
  std::shared_ptr<FitSession> keep_until_return;
  {
    std::lock_guard lock(mu_);
    keep_until_return = std::move(self_);
    // Known for certain only now (OnCancel and the failed read that a cancellation brings come
    // in either order): a client that went away before its status is CANCELLED, whatever
    // the server had decided meanwhile, such as the missing end marker of its cut-off stream.
    const bool client_went_away = context_->IsCancelled() && !cancelled_by_server_;
    const grpc::StatusCode code = client_went_away ? grpc::StatusCode::CANCELLED : finished_with_;
    if (unended_input_error_ && !client_went_away) {
      log_session_error(unended_input_error_->code, unended_input_error_->field);
    }
    metrics_.session_finished(tenant_, status_code_name(code));
    const double seconds = std::chrono::duration<double>(Clock::now() - started_at_).count();
    log_event("info", "session_end",
              {{"session", std::to_string(id_)},
               {"status", status_code_name(code)},
               {"chunks", std::to_string(chunks_read_)},
               {"item_errors", std::to_string(item_errors_)},
               {"seconds", std::to_string(seconds)}});
  }
  registry_.release(id_);
}

}  // namespace posefuse::server
