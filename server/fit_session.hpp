#pragma once
// One Fit call: a gRPC callback reactor that feeds a SessionPipeline running on the worker pool.
//
// Threads: gRPC calls OnReadDone/OnWriteDone/OnCancel on its reactor threads; these only move
// messages between queues and schedule work. The pipeline runs in work() on the WorkerPool, at
// most one task per session at a time, so a session's chunks are processed in order.
//
// Back-pressure, both ways:
//  - input: at most max_queued_chunks chunks wait for the pipeline; at the bound no new Read is
//    started until the worker has taken one, so a fast client is slowed down by HTTP/2 flow
//    control instead of making the server buffer the recording;
//  - output: when max_queued_results results wait to be sent (the client reads slowly), the
//    worker stops taking chunks until the writes catch up.
//
// Ending: the end marker processed -> OK after the last result is sent; a session-ending
// posefuse::Error -> its status (after the results before it); client cancellation -> work stops
// and the call finishes CANCELLED; no chunk for idle_timeout_s -> DEADLINE_EXCEEDED; data that
// advances slower than min_stream_rate x real time after stream_rate_grace_s (stream_rate.hpp)
// -> DEADLINE_EXCEEDED after the results before it. A session whose status is decided but whose
// client stops taking the results before it is cancelled after idle_timeout_s as well.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include <grpcpp/grpcpp.h>

#include "posefuse/v1/service.grpc.pb.h"
#include "server/metrics.hpp"
#include "server/server_options.hpp"
#include "server/session_registry.hpp"
#include "server/worker_pool.hpp"
#include "session/pipeline.hpp"

namespace posefuse::server {

class FitSession : public grpc::ServerBidiReactor<v1::SessionChunk, v1::FitResult>,
                   public SupervisedSession,
                   public std::enable_shared_from_this<FitSession> {
 public:
  // Starts the call; the returned reactor keeps itself alive until OnDone.
  // `tenant` is the caller's, for the metrics.
  static FitSession* start(grpc::CallbackServerContext* context, std::uint64_t id, std::string tenant,
                           const ServerOptions& options, WorkerPool& pool, SessionRegistry& registry, Metrics& metrics);

  void OnReadDone(bool ok) override;
  void OnWriteDone(bool ok) override;
  void OnCancel() override;
  void OnDone() override;
  // The idle timeout and the minimum stream rate (called by the registry's monitor).
  void check_idle(std::chrono::steady_clock::time_point now) override;

  // Use start(); public only for make_shared.
  FitSession(grpc::CallbackServerContext* context, std::uint64_t id, std::string tenant, const ServerOptions& options,
             WorkerPool& pool, SessionRegistry& registry, Metrics& metrics);

 private:
  class Sink;
  using Clock = std::chrono::steady_clock;

  void work();
  void schedule_locked();
  void start_read_locked();
  void enqueue_result(v1::FitResult&& result);
  void start_write_locked();
  // Sends `status` once every queued result is out; stops taking chunks.
  void finish_after_writes_locked(grpc::Status status);
  void finish_now_locked(grpc::Status status);
  void log_session_error(const std::string& code, const std::string& field) const;
  void clear_inbox_locked();
  // The worker task returns; its time since schedule_locked was the server's, not the client's.
  void worker_returns_locked();
  // Ends the session if its client has fallen below the minimum stream rate.
  void check_stream_rate_locked(Clock::time_point now);

  grpc::CallbackServerContext* const context_;
  const std::uint64_t id_;
  const std::string tenant_;
  const ServerOptions& options_;
  WorkerPool& pool_;
  SessionRegistry& registry_;
  Metrics& metrics_;
  const Clock::time_point started_at_ = Clock::now();

  std::mutex mu_;
  std::shared_ptr<FitSession> self_;  // released in OnDone
  v1::SessionChunk read_buffer_;
  bool read_pending_ = false;
  bool input_closed_ = false;  // the client half-closed (or the read side failed)
  std::deque<v1::SessionChunk> inbox_;
  std::atomic<std::uint64_t> inbox_bytes_{0};  // for the session's memory budget (read unlocked)
  bool worker_scheduled_ = false;
  Clock::time_point worker_scheduled_at_;
  // Wall time the worker was scheduled or running: the server's share of the session's time,
  // which the minimum stream rate does not charge to the client.
  Clock::duration server_busy_{};
  std::int64_t stream_time_us_ = 0;  // the pipeline's, as of the worker's last chunk
  bool worker_waits_for_writes_ = false;
  std::deque<v1::FitResult> outbox_;
  v1::FitResult write_buffer_;
  bool write_pending_ = false;
  std::optional<grpc::Status> final_status_;  // decided; sent once the outbox is empty
  bool finished_ = false;                     // Finish() was called
  grpc::StatusCode finished_with_ = grpc::StatusCode::OK;
  bool cancelled_by_server_ = false;  // the idle timeout cancelled the call, not the client
  struct SessionError {
    std::string code, field;
  };
  // The error of an input that ended without its end marker, logged in OnDone unless the
  // client went away.
  std::optional<SessionError> unended_input_error_;
  Clock::time_point last_read_at_ = Clock::now();
  std::uint64_t chunks_read_ = 0;  // for the log line
  std::uint64_t item_errors_ = 0;

  // Used only by the task running work() (one at a time).
  std::unique_ptr<Sink> sink_;
  std::unique_ptr<session::SessionPipeline> pipeline_;
};

}  // namespace posefuse::server
