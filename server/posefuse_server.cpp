#include "server/posefuse_server.hpp"

#include <chrono>
#include <cmath>
#include <thread>

#include <grpcpp/health_check_service_interface.h>

#include "common/error.hpp"
#include "grpc/health/v1/health.pb.h"
#include "server/deferred_job_store.hpp"
#include "server/log.hpp"
#include "server/pg_job_store.hpp"
#include "server/security.hpp"
#include "server/session_memory.hpp"
#include "server/sqlite_job_store.hpp"
#include "server/submit_job_call.hpp"
#include "server/upload_spool.hpp"

namespace posefuse::server {

namespace {

std::chrono::milliseconds seconds_to_ms(double seconds) {
  return std::chrono::milliseconds(static_cast<std::int64_t>(std::llround(seconds * 1000.0)));
}

}  // namespace

void validate_options(const ServerOptions& o) {
  if (o.listen.empty()) throw_invalid("--listen", "is empty; expected host:port");
  if (o.max_sessions == 0) throw_invalid("--max-sessions", "must be at least 1");
  if (o.tenant_max_sessions > o.max_sessions) {
    throw_invalid("--tenant-max-sessions", "is " + std::to_string(o.tenant_max_sessions) + ", above --max-sessions (" +
                                               std::to_string(o.max_sessions) + "); 0 splits those evenly");
  }
  if (!(o.max_message_mb > 0.0 && o.max_message_mb <= 1024.0)) {
    throw_invalid("--max-message-mb", "is " + std::to_string(o.max_message_mb) + ", must be in (0, 1024]");
  }
  if (!(o.idle_timeout_s > 0.0 && std::isfinite(o.idle_timeout_s))) {
    throw_invalid("--idle-timeout-s", "must be a positive number of seconds");
  }
  if (!(o.min_stream_rate >= 0.0 && std::isfinite(o.min_stream_rate))) {
    throw_invalid("--min-stream-rate", "must be >= 0 (seconds of recording per wall second; 0 disables)");
  }
  if (!(o.stream_rate_grace_s > 0.0 && std::isfinite(o.stream_rate_grace_s))) {
    throw_invalid("--stream-rate-grace-s", "must be a positive number of seconds");
  }
  if (o.max_queued_chunks == 0) throw_invalid("--max-queued-chunks", "must be at least 1");
  if (!(o.max_session_memory_mb >= 0.0 && o.max_session_memory_mb <= 1024.0 * 1024.0)) {
    throw_invalid("--max-session-memory-mb",
                  "is " + std::to_string(o.max_session_memory_mb) +
                      ", must be in [0, 1048576] (MiB; 0: a share of this machine's memory)");
  }
  if (o.max_queued_results == 0) throw_invalid("--max-queued-results", "must be at least 1");
  if (o.max_jobs == 0) throw_invalid("--max-jobs", "must be at least 1");
  if (!(o.max_upload_mb > 0.0 && o.max_upload_mb <= 1024.0 * 1024.0)) {
    throw_invalid("--max-upload-mb",
                  "is " + std::to_string(o.max_upload_mb) + ", must be in (0, 1048576] (MiB; at most 1 TiB)");
  }
  if (!(o.max_spool_mb > 0.0 && o.max_spool_mb <= 1024.0 * 1024.0)) {
    throw_invalid("--max-spool-mb",
                  "is " + std::to_string(o.max_spool_mb) + ", must be in (0, 1048576] (MiB; at most 1 TiB)");
  }
  if (!(o.shutdown_grace_s >= 0.0 && std::isfinite(o.shutdown_grace_s))) {
    throw_invalid("--shutdown-grace-s", "must be >= 0 seconds");
  }
  if (o.tls_cert.empty() != o.tls_key.empty()) {
    throw_invalid(o.tls_cert.empty() ? "--tls-cert" : "--tls-key", "is missing: --tls-cert and --tls-key go together");
  }
  if (o.role != "api" && o.role != "worker" && o.role != "both") {
    throw_invalid("--role", "is '" + o.role + "'; expected api, worker or both");
  }
  if (!o.job_store.empty() && !is_postgres_conninfo(o.job_store)) {
    throw_invalid("--job-store",
                  "expected a PostgreSQL connection string (postgresql://... or "
                  "key=value ...); without it the job store is SQLite in --data-dir");
  }
  if (!o.job_store.empty() && o.data_dir.empty()) {
    throw_invalid("--job-store", "needs --data-dir (this replica's folder for uploads in transit)");
  }
  if (o.role != "both" && o.job_store.empty()) {
    throw_invalid("--role", o.role +
                                " needs a shared --job-store (PostgreSQL): with SQLite in "
                                "--data-dir no other process sees this one's jobs");
  }
  if (!(o.job_lease_s > 0.0 && o.job_lease_s <= 86400.0)) {
    throw_invalid("--job-lease-s", "must be in (0, 86400] seconds");
  }
  if (!(o.job_heartbeat_s > 0.0 && o.job_heartbeat_s < o.job_lease_s)) {
    throw_invalid("--job-heartbeat-s",
                  "must be positive and below --job-lease-s (a lease is "
                  "renewed before it expires)");
  }
  if (o.job_max_attempts == 0) throw_invalid("--job-max-attempts", "must be at least 1");
  if (!(o.job_deadline_s >= 0.0 && o.job_deadline_s <= 31.0 * 86400.0)) {
    throw_invalid("--job-deadline-s", "must be in [0, 2678400] seconds (0: no deadline)");
  }
  if (!(o.job_stall_s >= 0.0 && o.job_stall_s <= 31.0 * 86400.0)) {
    throw_invalid("--job-stall-s", "must be in [0, 2678400] seconds (0: no limit)");
  }
  if (!o.tls_client_ca.empty() && o.tls_cert.empty()) {
    throw_invalid("--tls-client-ca", "needs --tls-cert and --tls-key (mutual TLS is TLS first)");
  }
  // Recordings are patient data: beyond this machine only over TLS, and only to token holders.
  if (!o.insecure && !listens_on_loopback_only(o.listen) && (o.tls_cert.empty() || o.tokens_file.empty())) {
    const std::string missing = o.tls_cert.empty() && o.tokens_file.empty() ? "--tls-cert/--tls-key and --tokens-file"
                                : o.tls_cert.empty()                        ? "--tls-cert/--tls-key"
                                                                            : "--tokens-file";
    throw_invalid("--listen", "'" + o.listen +
                                  "' is not a loopback address, and serving beyond this machine needs TLS "
                                  "(--tls-cert, --tls-key) and tokens (--tokens-file); missing: " +
                                  missing + ". Give them, or --insecure to serve without");
  }
}

PoseFuseServer::PoseFuseServer(ServerOptions options, JobStoreFactory make_store) : options_(std::move(options)) {
  validate_options(options_);
  if (options_.max_session_memory_mb == 0.0) {
    options_.max_session_memory_mb = static_cast<double>(default_session_memory_bytes(
                                         usable_memory_bytes(), options_.max_sessions, options_.max_jobs)) /
                                     (1 << 20);
  }
  // Security files first: a bad one fails before any thread or port exists.
  const std::shared_ptr<grpc::ServerCredentials> credentials = make_server_credentials(options_);
  if (!options_.tokens_file.empty()) {
    tokens_ = std::make_unique<BearerTokens>(BearerTokens::load(options_.tokens_file));
  }
  const unsigned workers = options_.workers > 0 ? options_.workers : std::max(1u, std::thread::hardware_concurrency());
  pool_ = std::make_unique<WorkerPool>(workers);
  // The idle check runs a few times per timeout, at most every 250 ms.
  const auto check_interval =
      std::chrono::milliseconds(static_cast<long>(std::clamp(options_.idle_timeout_s * 1000.0 / 4.0, 10.0, 250.0)));
  const unsigned tenant_max_sessions =
      options_.tenant_max_sessions > 0
          ? options_.tenant_max_sessions
          : fair_share_of_sessions(options_.max_sessions, tokens_ ? tokens_->tenants().size() : 1);
  registry_ = std::make_unique<SessionRegistry>(options_.max_sessions, tenant_max_sessions, check_interval);
  if (!options_.data_dir.empty()) {
    std::error_code error;
    std::filesystem::create_directories(upload_spool_dir(options_.data_dir), error);
    if (error) {
      throw Error(ErrorCode::kFailedPrecondition, "--data-dir",
                  "cannot create '" + options_.data_dir + "' and its uploads/ folder: " + error.message());
    }
    // Uploads that a stopped server was receiving never became jobs: their clients got no job
    // id and send again.
    if (const std::size_t removed = remove_partial_uploads(upload_spool_dir(options_.data_dir))) {
      log_event("info", "partial_uploads_removed", {{"count", std::to_string(removed)}});
    }
    const std::filesystem::path data_dir(options_.data_dir);
    // Uploads fetched from a shared store for a job that this replica no longer runs.
    std::filesystem::remove_all(data_dir / "fetched", error);
    std::filesystem::create_directories(data_dir / "fetched", error);
    // A store that cannot be opened now (a full disk, PostgreSQL away) leaves the server up
    // with the jobs' health NOT_SERVING; the heartbeat opens it once it can.
    auto store = std::make_unique<DeferredJobStore>([this, data_dir, make_store]() -> std::unique_ptr<JobStore> {
      if (make_store) return make_store(data_dir);
      if (!options_.job_store.empty()) {
        // A connection per running job's writes, one for the dispatcher's claims and heartbeats,
        // two for API calls and watchers' reads.
        return std::make_unique<PgJobStore>(options_.job_store, options_.max_jobs + 3);
      }
      return std::make_unique<SqliteJobStore>(data_dir / "jobs.sqlite");
    });
    job_store_problem_ = store->problem();
    job_store_ = std::move(store);
    JobRunnerOptions runner;
    runner.max_running = options_.max_jobs;
    runner.claims_jobs = options_.role != "api";
    runner.recordings_root = options_.recordings_root;
    runner.scratch_dir = data_dir / "fetched";
    runner.lease = seconds_to_ms(options_.job_lease_s);
    runner.heartbeat = seconds_to_ms(options_.job_heartbeat_s);
    runner.max_attempts = options_.job_max_attempts;
    runner.max_held_bytes = session_memory_bytes(options_);
    runner.deadline = seconds_to_ms(options_.job_deadline_s);
    runner.stall = seconds_to_ms(options_.job_stall_s);
    jobs_ = std::make_unique<JobRunner>(*job_store_, metrics_, std::move(runner));
  }
  service_ = std::make_unique<PoseFuseService>(options_, *pool_, *registry_, metrics_, jobs_.get(), tokens_.get());

  // Before the gRPC server, so that a bad --metrics-listen fails before anything serves.
  if (!options_.metrics_listen.empty()) {
    metrics_http_ = std::make_unique<MetricsHttpServer>(options_.metrics_listen, [this] { return render_metrics(); });
    log_event("info", "metrics_start", {{"port", std::to_string(metrics_http_->port())}});
  }

  // Naming a health message links health.proto's descriptor into the server, so that
  // reflection can describe the health service as well as answer its name.
  reflection_ = std::make_unique<ReflectionService>(
      std::vector<std::string>{v1::PoseFuse::service_full_name(),
                               grpc::health::v1::HealthCheckRequest::descriptor()->file()->service(0)->full_name(),
                               reflection::ServerReflection::service_full_name()},
      tokens_.get());

  grpc::EnableDefaultHealthCheckService(true);
  grpc::ServerBuilder builder;
  builder.AddListeningPort(options_.listen, credentials, &port_);
  builder.RegisterService(service_.get());
  builder.RegisterService(reflection_.get());
  builder.SetMaxReceiveMessageSize(static_cast<int>(options_.max_message_mb * 1024 * 1024));
  server_ = builder.BuildAndStart();
  if (!server_ || port_ == 0) {
    throw Error(
        ErrorCode::kFailedPrecondition, "--listen",
        "cannot listen on '" + options_.listen + "' (address in use or invalid?" +
            (options_.tls_cert.empty() ? std::string(")")
                                       : std::string(" or --tls-cert and --tls-key are not a matching pair?)")));
  }
  // The overall status ("") and the PoseFuse service's own, so that a probe may ask either;
  // shutdown() turns both to NOT_SERVING.
  grpc::HealthCheckServiceInterface& health = *server_->GetHealthCheckService();
  health.SetServingStatus(v1::PoseFuse::service_full_name(), true);
  health.SetServingStatus(true);
  // The jobs' own status follows the job store; Fit and the overall status do not depend on it.
  if (jobs_) {
    health.SetServingStatus(kJobsHealthService, job_store_problem_.empty());
    jobs_->start([&health](bool serving) { health.SetServingStatus(kJobsHealthService, serving); });
  }
  log_event("info", "server_start",
            {{"listen", options_.listen},
             {"port", std::to_string(port_)},
             {"workers", std::to_string(workers)},
             {"max_sessions", std::to_string(options_.max_sessions)},
             {"tenant_max_sessions", std::to_string(tenant_max_sessions)},
             {"max_session_memory_mb", std::to_string(std::lround(options_.max_session_memory_mb))},
             {"max_message_mb", std::to_string(options_.max_message_mb)},
             {"idle_timeout_s", std::to_string(options_.idle_timeout_s)},
             {"min_stream_rate", std::to_string(options_.min_stream_rate)},
             {"stream_rate_grace_s", std::to_string(options_.stream_rate_grace_s)},
             {"role", options_.role},
             {"job_store", !jobs_                       ? "off"
                           : options_.job_store.empty() ? "sqlite"
                                                        : "postgresql"}});
  // The security mode, never a token or key.
  log_event("info", "security",
            {{"transport", transport_mode(options_)},
             {"auth", tokens_ ? "bearer_token" : "none"},
             {"tokens", std::to_string(tokens_ ? tokens_->size() : 0)}});
  if (options_.insecure && !listens_on_loopback_only(options_.listen) && (!tokens_ || options_.tls_cert.empty())) {
    log_event("warning", "insecure_listen", {{"listen", options_.listen}});
  }
}

PoseFuseServer::~PoseFuseServer() { shutdown(); }

std::string PoseFuseServer::render_metrics() const {
  return metrics_.render({registry_->active(), pool_->queued(), static_cast<unsigned>(pool_->threads()),
                          service_->spool_quota().in_use()});
}

std::vector<std::string> PoseFuseServer::shutdown() {
  if (shut_down_) return blocked_jobs_;
  shut_down_ = true;
  log_event("info", "server_shutdown", {{"sessions", std::to_string(registry_->active())}});
  // Every service NOT_SERVING, and no later change (the job store's health) turns one back.
  server_->GetHealthCheckService()->Shutdown();
  const auto grace =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::duration<double>(options_.shutdown_grace_s));
  server_->Shutdown(std::chrono::system_clock::now() + grace);
  metrics_http_.reset();
  // Running jobs stop between chunks and go back to the queue; one blocked inside a read is
  // left to its lease.
  if (jobs_) blocked_jobs_ = jobs_->stop(grace);
  if (blocked_jobs_.empty()) {
    jobs_.reset();
    log_event("info", "server_stopped");
  } else {
    std::string ids;
    for (const std::string& id : blocked_jobs_) ids += (ids.empty() ? "" : ",") + id;
    log_event(
        "warning", "server_stopped_with_blocked_jobs",
        {{"jobs", ids}, {"reason", "each is blocked inside a read; its lease expires and another worker resumes it"}});
  }
  return blocked_jobs_;
}

void PoseFuseServer::wait() { server_->Wait(); }

}  // namespace posefuse::server
