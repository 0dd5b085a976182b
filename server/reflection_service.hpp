#pragma once
// grpc.reflection.v1alpha.ServerReflection (server/proto/grpc/reflection/v1alpha/
// reflection.proto) answered from the protobuf descriptors linked into the server. Written here
// rather than taken from libgrpc++_reflection so that, like every posefuse call and unlike the
// health service, it requires the bearer token when the server has tokens: reflection tells a
// caller the whole API, which only clients that may use it need to see.
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "grpc/reflection/v1alpha/reflection.grpc.pb.h"
#include "server/security.hpp"

namespace posefuse::server {

namespace reflection = grpc::reflection::v1alpha;

class ReflectionService final : public reflection::ServerReflection::CallbackService {
 public:
  // `services`: the fully-qualified names list_services answers. `tokens` may be null (open).
  ReflectionService(std::vector<std::string> services, const BearerTokens* tokens);

  grpc::ServerBidiReactor<reflection::ServerReflectionRequest, reflection::ServerReflectionResponse>*
  ServerReflectionInfo(grpc::CallbackServerContext* context) override;

 private:
  std::vector<std::string> services_;
  const BearerTokens* tokens_;
};

// The answer to one request (from the generated descriptor pool); NOT_FOUND and
// INVALID_ARGUMENT come back as error_response, as the protocol says.
reflection::ServerReflectionResponse answer_reflection_request(const reflection::ServerReflectionRequest& request,
                                                               const std::vector<std::string>& services);

}  // namespace posefuse::server
