#pragma once
// The one error type core code throws for bad input or impossible requests.
//
// Every error names what is wrong (`field`) and why, so that the server can map it to a gRPC
// status (INVALID_ARGUMENT, FAILED_PRECONDITION, ...) and the client can print one readable line.
#include <stdexcept>
#include <string>

namespace posefuse {

enum class ErrorCode {
  kInvalidArgument,     // malformed input: NaN, wrong size, out-of-order timestamps, bad enum
  kFailedPrecondition,  // input is well-formed but the stage cannot work with it (e.g. poor coverage)
  kOutOfRange,          // a value outside its documented range
  kNotFound,            // a file, stream or key that should exist does not
  kDataLoss,            // truncated or corrupt data
  kResourceExhausted,   // a size or count limit was exceeded
  kInternal,            // a bug: an invariant of our own code does not hold
};

const char* error_code_name(ErrorCode code);

class Error : public std::runtime_error {
 public:
  // `field` names the offending input, e.g. "imu_batch[3].t_us" or "mag_samples".
  Error(ErrorCode code, std::string field, const std::string& message);

  ErrorCode code() const { return code_; }
  const std::string& field() const { return field_; }

 private:
  ErrorCode code_;
  std::string field_;
};

// Shorthands for the common cases.
[[noreturn]] void throw_invalid(const std::string& field, const std::string& message);
[[noreturn]] void throw_precondition(const std::string& field, const std::string& message);

}  // namespace posefuse
