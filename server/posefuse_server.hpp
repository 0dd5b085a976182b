#pragma once
// A running posefuse server: the gRPC server with the PoseFuse service, the standard health
// service (grpc.health.v1) and server reflection (reflection_service.hpp), the worker pool and
// the session registry. Used by posefuse-server's main and, in-process, by the integration
// tests.
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "server/job_runner.hpp"
#include "server/job_store.hpp"
#include "server/metrics.hpp"
#include "server/metrics_http.hpp"
#include "server/posefuse_service.hpp"
#include "server/reflection_service.hpp"
#include "server/security.hpp"
#include "server/server_options.hpp"
#include "server/session_registry.hpp"
#include "server/worker_pool.hpp"

namespace posefuse::server {

// Makes the job store in --data-dir. The default opens <data-dir>/jobs.sqlite; tests pass one
// that wraps it to inject faults.
using JobStoreFactory = std::function<std::unique_ptr<JobStore>(const std::filesystem::path& data_dir)>;

// The health service name of the batch jobs: SERVING while the job store takes writes,
// NOT_SERVING while it does not (or cannot be opened); "" and posefuse.v1.PoseFuse stay SERVING.
inline constexpr const char* kJobsHealthService = "posefuse.v1.PoseFuse.Jobs";

class PoseFuseServer {
 public:
  // Binds and starts serving. Throws posefuse::Error (kInvalidArgument naming the option) for
  // bad options, kFailedPrecondition when the address cannot be bound.
  explicit PoseFuseServer(ServerOptions options, JobStoreFactory make_store = {});
  ~PoseFuseServer();  // shuts down if still running

  // The bound port (useful with port 0).
  int port() const { return port_; }
  const ServerOptions& options() const { return options_; }
  SessionRegistry& registry() { return *registry_; }
  const SpoolQuota& spool_quota() const { return service_->spool_quota(); }
  JobRunner* jobs() { return jobs_.get(); }
  // The metrics endpoint's port, 0 when it is off.
  int metrics_port() const { return metrics_http_ ? metrics_http_->port() : 0; }
  std::string render_metrics() const;

  // Health NOT_SERVING, stop accepting calls, give calls in flight shutdown_grace_s to finish,
  // then cancel them; then give running jobs shutdown_grace_s to go back to the queue.
  // Idempotent. Returns the ids of the jobs still running after that, each blocked inside a
  // read: while any is, this server must not be destroyed (posefuse-server's main exits
  // without destroying it, and their leases expire).
  std::vector<std::string> shutdown();
  // Blocks until shutdown() has completed.
  void wait();

 private:
  ServerOptions options_;
  Metrics metrics_;
  std::unique_ptr<WorkerPool> pool_;
  std::unique_ptr<SessionRegistry> registry_;
  std::unique_ptr<JobStore> job_store_;
  std::string job_store_problem_;  // why the store could not be opened at start ("" when it was)
  std::unique_ptr<JobRunner> jobs_;
  std::unique_ptr<BearerTokens> tokens_;  // null: no token needed
  std::unique_ptr<PoseFuseService> service_;
  std::unique_ptr<ReflectionService> reflection_;
  std::unique_ptr<grpc::Server> server_;
  std::unique_ptr<MetricsHttpServer> metrics_http_;
  int port_ = 0;
  bool shut_down_ = false;
  std::vector<std::string> blocked_jobs_;  // shutdown()'s result
};

// Checks option values; throws kInvalidArgument naming the flag ("--workers").
void validate_options(const ServerOptions& options);

}  // namespace posefuse::server
