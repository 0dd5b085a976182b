#pragma once
// The posefuse.v1.PoseFuse service on gRPC's callback API. Fit runs FitSession; GetServerInfo
// answers from the options and the default stages. The job calls are not implemented yet and
// answer UNIMPLEMENTED (the generated base class's default).
#include <grpcpp/grpcpp.h>

#include "posefuse/v1/service.grpc.pb.h"
#include "server/server_options.hpp"
#include "server/session_registry.hpp"
#include "server/worker_pool.hpp"

namespace posefuse::server {

class PoseFuseService final : public v1::PoseFuse::CallbackService {
 public:
  PoseFuseService(const ServerOptions& options, WorkerPool& pool, SessionRegistry& registry);

  grpc::ServerBidiReactor<v1::SessionChunk, v1::FitResult>* Fit(
      grpc::CallbackServerContext* context) override;
  grpc::ServerUnaryReactor* GetServerInfo(grpc::CallbackServerContext* context,
                                          const v1::GetServerInfoRequest* request,
                                          v1::ServerInfo* response) override;

 private:
  const ServerOptions& options_;
  WorkerPool& pool_;
  SessionRegistry& registry_;
};

// What GetServerInfo returns (also used by tests).
v1::ServerInfo server_info(const ServerOptions& options, unsigned workers);

}  // namespace posefuse::server
