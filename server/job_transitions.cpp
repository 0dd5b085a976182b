#include "server/job_transitions.hpp"

#include <grpcpp/support/status.h>

#include "common/error.hpp"
#include "server/random_id.hpp"

namespace posefuse::server {

bool is_terminal(v1::Job::State state) {
  return state == v1::Job::SUCCEEDED || state == v1::Job::FAILED || state == v1::Job::CANCELLED;
}

v1::Job new_job(const v1::JobSpec& spec, std::int64_t now_unix_us) {
  v1::Job job;
  job.set_job_id(random_hex_id());
  job.set_state(v1::Job::QUEUED);
  job.set_create_time_unix_us(now_unix_us);
  job.set_update_time_unix_us(now_unix_us);
  job.set_label(spec.label());
  if (spec.has_recording_uri()) job.set_recording_uri(spec.recording_uri());
  return job;
}

v1::Job parse_stored_job(const std::string& bytes, const std::string& field) {
  v1::Job job;
  if (!job.ParseFromString(bytes)) throw Error(ErrorCode::kDataLoss, field, "stored job does not parse");
  return job;
}

void mark_claimed(v1::Job& job, std::int64_t now_unix_us) {
  job.set_state(v1::Job::RUNNING);
  job.clear_progress();
  job.set_update_time_unix_us(now_unix_us);
}

void mark_queued_again(v1::Job& job, std::int64_t now_unix_us) {
  job.set_state(v1::Job::QUEUED);
  job.clear_progress();
  job.set_update_time_unix_us(now_unix_us);
}

void mark_cancelled(v1::Job& job, std::int64_t now_unix_us) {
  job.set_state(v1::Job::CANCELLED);
  job.set_update_time_unix_us(now_unix_us);
}

v1::Job::State mark_lease_expired(v1::Job& job, std::uint32_t attempts, std::uint32_t max_attempts,
                                  bool cancel_requested, std::int64_t now_unix_us) {
  if (cancel_requested) {
    mark_cancelled(job, now_unix_us);
  } else if (attempts >= max_attempts) {
    job.set_state(v1::Job::FAILED);
    job.set_error_code(static_cast<int>(grpc::StatusCode::ABORTED));
    job.set_error_message("job: its worker's lease expired " + std::to_string(attempts) +
                          (attempts == 1 ? " time" : " times") +
                          " (the worker stopped or lost the job store each time; "
                          "--job-max-attempts " +
                          std::to_string(max_attempts) + "); not run again");
    job.set_update_time_unix_us(now_unix_us);
  } else {
    mark_queued_again(job, now_unix_us);
  }
  return job.state();
}

}  // namespace posefuse::server
