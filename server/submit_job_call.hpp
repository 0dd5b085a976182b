#pragma once
// SubmitJob on the callback API: by reference (resolve the recording under the recordings root,
// store the job, answer at once) or by upload (the session's chunks follow the JobSpec; see
// docs/server.md "Jobs by upload").
//
// An upload is a session like a Fit call: it takes a --max-sessions slot (beyond it
// RESOURCE_EXHAUSTED) and the idle timeout applies (no message for idle_timeout_s ->
// DEADLINE_EXCEEDED). Each chunk read goes to the UploadSpool on the worker pool (validation
// decodes images: never on a reactor thread) and only then is the next one read, so one chunk
// is held per upload and a fast client is slowed by HTTP/2 flow control. The job is stored once
// the whole session has arrived; a refused, truncated, idle or cancelled upload leaves nothing.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>

#include <grpcpp/grpcpp.h>

#include "posefuse/v1/service.grpc.pb.h"
#include "server/job_runner.hpp"
#include "server/metrics.hpp"
#include "server/session_registry.hpp"
#include "server/upload_spool.hpp"
#include "server/worker_pool.hpp"

namespace posefuse::server {

// Where uploaded recordings are spooled: <data_dir>/uploads.
inline std::filesystem::path upload_spool_dir(const std::string& data_dir) {
  return std::filesystem::path(data_dir) / "uploads";
}

// What SubmitJob needs; lives as long as the service.
struct SubmitJobContext {
  JobRunner& runner;
  WorkerPool& pool;
  SessionRegistry& registry;
  Metrics& metrics;
  std::filesystem::path recordings_root;  // by reference: empty = off
  // The tokens file names tenants: each submits by reference from its own folder of the root
  // only, and the tenant "" (tokens without one) cannot (server/job_recording.hpp).
  bool tenant_folders;
  std::filesystem::path spool_dir;  // by upload: where the chunk files go
  std::uint64_t max_upload_bytes;
  SpoolQuota& spool_quota;  // the uploads in transit, together (--max-spool-mb)
  std::chrono::duration<double> idle_timeout;
};

class SubmitJobCall : public grpc::ServerReadReactor<v1::SubmitJobRequest>,
                      public SupervisedSession,
                      public std::enable_shared_from_this<SubmitJobCall> {
 public:
  // Starts the call; the returned reactor keeps itself alive until OnDone.
  // The job belongs to `tenant`.
  static SubmitJobCall* start(const SubmitJobContext& context, v1::Job* response, std::string tenant);

  void OnReadDone(bool ok) override;
  void OnCancel() override;
  void OnDone() override;
  void check_idle(std::chrono::steady_clock::time_point now) override;

  // Use start(); public only for make_shared.
  SubmitJobCall(const SubmitJobContext& context, v1::Job* response, std::string tenant);

 private:
  using Clock = std::chrono::steady_clock;

  void read_spec_locked(bool ok);
  void add_chunk();  // worker
  void commit();     // worker
  void start_read_locked();
  void finish_locked(grpc::Status status);

  const SubmitJobContext& context_;
  v1::Job* response_;
  const std::string tenant_;
  std::mutex mu_;
  std::shared_ptr<SubmitJobCall> self_;  // released in OnDone
  v1::SubmitJobRequest request_;
  v1::JobSpec spec_;
  std::unique_ptr<UploadSpool> spool_;  // set while an upload is arriving
  std::optional<std::uint64_t> slot_;   // the upload's session slot
  bool read_pending_ = false;
  bool cancelled_ = false;
  bool finished_ = false;
  Clock::time_point last_read_at_ = Clock::now();
};

}  // namespace posefuse::server
