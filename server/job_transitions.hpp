#pragma once
// How a stored job message changes when the queue acts on it: the same in every JobStore, so
// that SQLite and PostgreSQL report the same states and messages.
#include <cstdint>
#include <string>

#include "posefuse/v1/service.pb.h"

namespace posefuse::server {

bool is_terminal(v1::Job::State state);

// A new QUEUED job with a fresh random id.
v1::Job new_job(const v1::JobSpec& spec, std::int64_t now_unix_us);
// Throws kDataLoss naming `field` for bytes that do not parse.
v1::Job parse_stored_job(const std::string& bytes, const std::string& field);

void mark_claimed(v1::Job& job, std::int64_t now_unix_us);
void mark_queued_again(v1::Job& job, std::int64_t now_unix_us);
void mark_cancelled(v1::Job& job, std::int64_t now_unix_us);
// The state a job whose lease expired goes to, and the job changed accordingly.
v1::Job::State mark_lease_expired(v1::Job& job, std::uint32_t attempts, std::uint32_t max_attempts,
                                  bool cancel_requested, std::int64_t now_unix_us);

}  // namespace posefuse::server
