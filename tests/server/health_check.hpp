#pragma once
// One grpc.health.v1 Check call for the server tests (needs posefuse_health_proto, which
// posefuse_client_lib brings).
#include <memory>

#include <grpcpp/grpcpp.h>

#include "grpc/health/v1/health.grpc.pb.h"
#include "tests/server/test_support.hpp"

namespace posefuse::test {

inline grpc::Status check_health(const std::shared_ptr<grpc::Channel>& channel,
                                 grpc::health::v1::HealthCheckResponse* response) {
  auto health = grpc::health::v1::Health::NewStub(channel);
  grpc::ClientContext context;
  set_test_deadline(context);
  return health->Check(&context, {}, response);
}

}  // namespace posefuse::test
