#pragma once
// grpc.health.v1 Check calls for the server tests (needs posefuse_health_proto, which
// posefuse_client_lib brings).
#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include <grpcpp/grpcpp.h>

#include "grpc/health/v1/health.grpc.pb.h"
#include "tests/server/test_support.hpp"

namespace posefuse::test {

// The status of `service` ("" = the server as a whole).
inline grpc::Status check_health(const std::shared_ptr<grpc::Channel>& channel,
                                 grpc::health::v1::HealthCheckResponse* response, const std::string& service = "") {
  auto health = grpc::health::v1::Health::NewStub(channel);
  grpc::ClientContext context;
  set_test_deadline(context);
  grpc::health::v1::HealthCheckRequest request;
  request.set_service(service);
  return health->Check(&context, request, response);
}

// The serving status of `service`, UNKNOWN when the call fails.
inline grpc::health::v1::HealthCheckResponse::ServingStatus serving_status(
    const std::shared_ptr<grpc::Channel>& channel, const std::string& service) {
  grpc::health::v1::HealthCheckResponse response;
  if (!check_health(channel, &response, service).ok()) return grpc::health::v1::HealthCheckResponse::UNKNOWN;
  return response.status();
}

// Polls until `service` reports `expected`; false when it has not within 60 s (a guard against
// hangs: the tests' heartbeats are a fraction of a second).
inline bool wait_for_health(const std::shared_ptr<grpc::Channel>& channel, const std::string& service,
                            grpc::health::v1::HealthCheckResponse::ServingStatus expected) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (serving_status(channel, service) != expected) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return true;
}

}  // namespace posefuse::test
