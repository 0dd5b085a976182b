#pragma once
// Store errors the job runner and the calls must tell apart from posefuse::Error's codes.
#include <string>

#include "common/error.hpp"

namespace posefuse::server {

// The store cannot be reached (PostgreSQL down or restarting): nothing about the job is
// known to be wrong, so a call answers UNAVAILABLE and a running job is handed back to its
// lease (another attempt runs it) instead of failing.
class StoreUnavailable : public Error {
 public:
  explicit StoreUnavailable(const std::string& message) : Error(ErrorCode::kFailedPrecondition, "job_store", message) {}
};

// A store that can never open as configured (another server process holds the SQLite file,
// a PostgreSQL schema newer than this binary): the server does not start. Any other failure to
// open is a condition that may pass (a full disk, the database away), retried on the heartbeat.
class StoreMisconfigured : public Error {
 public:
  StoreMisconfigured(const std::string& field, const std::string& message)
      : Error(ErrorCode::kFailedPrecondition, field, message) {}
};

// A worker's write under a lease that no longer holds the job (it expired and another attempt
// took the job, or the job was cancelled while the worker was away).
class LeaseLost : public Error {
 public:
  explicit LeaseLost(const std::string& job_id)
      : Error(ErrorCode::kFailedPrecondition, "job_store",
              "job '" + job_id + "': this worker's lease no longer holds it") {}
};

}  // namespace posefuse::server
