#pragma once
// posefuse::Error -> gRPC status (docs/architecture.md, "Errors"). The message is the error's
// "field: message" line unchanged, so the client can print it as one readable line.
#include <grpcpp/support/status.h>

#include "common/error.hpp"

namespace posefuse::server {

grpc::StatusCode status_code(ErrorCode code);
grpc::Status to_status(const Error& error);
// "INVALID_ARGUMENT", ... for logs and metrics labels ("OTHER" for codes the server never uses).
const char* status_code_name(grpc::StatusCode code);

}  // namespace posefuse::server
