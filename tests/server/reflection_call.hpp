#pragma once
// One request on grpc.reflection.v1alpha.ServerReflectionInfo, for the server tests.
#include <memory>

#include <grpcpp/grpcpp.h>

#include "grpc/reflection/v1alpha/reflection.grpc.pb.h"
#include "tests/server/test_support.hpp"

namespace posefuse::test {

// Sends `request`, reads the one answer into `response`, returns the call's status.
inline grpc::Status ask_reflection(const std::shared_ptr<grpc::Channel>& channel,
                                   const grpc::reflection::v1alpha::ServerReflectionRequest& request,
                                   grpc::reflection::v1alpha::ServerReflectionResponse* response) {
  auto stub = grpc::reflection::v1alpha::ServerReflection::NewStub(channel);
  grpc::ClientContext context;
  set_test_deadline(context);
  auto stream = stub->ServerReflectionInfo(&context);
  stream->Write(request);
  stream->WritesDone();
  grpc::reflection::v1alpha::ServerReflectionResponse ignored;
  stream->Read(response ? response : &ignored);
  return stream->Finish();
}

}  // namespace posefuse::test
