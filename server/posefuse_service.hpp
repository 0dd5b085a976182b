#pragma once
// The posefuse.v1.PoseFuse service on gRPC's callback API. Fit runs FitSession; GetServerInfo
// answers from the options and the default stages. The job calls run on a JobRunner; without
// one (no --data-dir) they answer FAILED_PRECONDITION.
#include <grpcpp/grpcpp.h>

#include <optional>
#include "posefuse/v1/service.grpc.pb.h"

#include "server/job_runner.hpp"
#include "server/metrics.hpp"
#include "server/security.hpp"
#include "server/server_options.hpp"
#include "server/session_registry.hpp"
#include "server/spool_quota.hpp"
#include "server/submit_job_call.hpp"
#include "server/worker_pool.hpp"

namespace posefuse::server {

class PoseFuseService final : public v1::PoseFuse::CallbackService {
 public:
  // `jobs` may be null: batch jobs are off. `tokens` may be null: no bearer token is needed;
  // otherwise every call without an accepted one ends UNAUTHENTICATED before doing anything.
  PoseFuseService(const ServerOptions& options, WorkerPool& pool, SessionRegistry& registry, Metrics& metrics,
                  JobRunner* jobs, const BearerTokens* tokens);

  grpc::ServerBidiReactor<v1::SessionChunk, v1::FitResult>* Fit(grpc::CallbackServerContext* context) override;
  grpc::ServerUnaryReactor* GetServerInfo(grpc::CallbackServerContext* context, const v1::GetServerInfoRequest* request,
                                          v1::ServerInfo* response) override;

  grpc::ServerReadReactor<v1::SubmitJobRequest>* SubmitJob(grpc::CallbackServerContext* context,
                                                           v1::Job* response) override;
  grpc::ServerUnaryReactor* GetJob(grpc::CallbackServerContext* context, const v1::GetJobRequest* request,
                                   v1::Job* response) override;
  grpc::ServerUnaryReactor* ListJobs(grpc::CallbackServerContext* context, const v1::ListJobsRequest* request,
                                     v1::ListJobsResponse* response) override;
  grpc::ServerUnaryReactor* CancelJob(grpc::CallbackServerContext* context, const v1::CancelJobRequest* request,
                                      v1::Job* response) override;
  grpc::ServerWriteReactor<v1::Job>* WatchJob(grpc::CallbackServerContext* context,
                                              const v1::WatchJobRequest* request) override;
  grpc::ServerWriteReactor<v1::FitResult>* GetJobResults(grpc::CallbackServerContext* context,
                                                         const v1::GetJobResultsRequest* request) override;

  // The bytes that uploads in transit hold now, and their quota (--max-spool-mb).
  const SpoolQuota& spool_quota() const { return spool_quota_; }

 private:
  const ServerOptions& options_;
  WorkerPool& pool_;
  SessionRegistry& registry_;
  Metrics& metrics_;
  JobRunner* jobs_;
  const BearerTokens* tokens_;
  SpoolQuota spool_quota_;                          // the uploads in transit, together
  std::optional<SubmitJobContext> submit_context_;  // set when jobs are on

  // OK without tokens or with an accepted one; logs a refusal (peer and call, never the token).
  // `tenant`: the caller's tenant, whose jobs are the only ones the call sees.
  grpc::Status authenticate(const grpc::CallbackServerContext* context, const char* call, std::string& tenant) const;
};

// What GetServerInfo returns (also used by tests).
v1::ServerInfo server_info(const ServerOptions& options, unsigned workers, bool jobs);

}  // namespace posefuse::server
