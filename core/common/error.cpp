#include "common/error.hpp"

namespace posefuse {

const char* error_code_name(ErrorCode code) {
  switch (code) {
    case ErrorCode::kInvalidArgument: return "invalid argument";
    case ErrorCode::kFailedPrecondition: return "failed precondition";
    case ErrorCode::kOutOfRange: return "out of range";
    case ErrorCode::kNotFound: return "not found";
    case ErrorCode::kDataLoss: return "data loss";
    case ErrorCode::kResourceExhausted: return "resource exhausted";
    case ErrorCode::kInternal: return "internal";
  }
  return "unknown";
}

Error::Error(ErrorCode code, std::string field, const std::string& message)
    : std::runtime_error(field + ": " + message), code_(code), field_(std::move(field)) {}

void throw_invalid(const std::string& field, const std::string& message) {
  throw Error(ErrorCode::kInvalidArgument, field, message);
}

void throw_precondition(const std::string& field, const std::string& message) {
  throw Error(ErrorCode::kFailedPrecondition, field, message);
}

}  // namespace posefuse
