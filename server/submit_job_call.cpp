#include "server/submit_job_call.hpp"

#include "server/job_limits.hpp"
#include "server/job_recording.hpp"
#include "server/job_store_errors.hpp"
#include "server/log.hpp"
#include "server/random_id.hpp"
#include "server/status.hpp"
#include "session/pipeline.hpp"

namespace posefuse::server {

SubmitJobCall* SubmitJobCall::start(const SubmitJobContext& context, v1::Job* response, std::string tenant) {
  auto call = std::make_shared<SubmitJobCall>(context, response, std::move(tenant));
  call->self_ = call;
  std::lock_guard lock(call->mu_);
  call->start_read_locked();
  return call.get();
}

SubmitJobCall::SubmitJobCall(const SubmitJobContext& context, v1::Job* response, std::string tenant)
    : context_(context), response_(response), tenant_(std::move(tenant)) {}

void SubmitJobCall::start_read_locked() {
  read_pending_ = true;
  StartRead(&request_);
}

void SubmitJobCall::OnReadDone(bool ok) {
  std::lock_guard lock(mu_);
  read_pending_ = false;
  last_read_at_ = Clock::now();
  if (finished_) return;
  if (!spool_) {
    read_spec_locked(ok);
    return;
  }
  // Past the spec: a worker adds the chunk (or commits at the end), then reads on.
  context_.pool.submit([self = shared_from_this(), ok] { ok ? self->add_chunk() : self->commit(); });
}

void SubmitJobCall::read_spec_locked(bool ok) {
  if (!ok || !request_.has_spec()) {
    finish_locked(
        grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, "spec: the first SubmitJobRequest must be a JobSpec"));
    return;
  }
  spec_ = request_.spec();
  try {
    validate_job_spec(spec_);
    if (spec_.source_case() == v1::JobSpec::kRecordingUri) {
      if (context_.tenant_folders && tenant_.empty()) {
        throw Error(ErrorCode::kFailedPrecondition, "spec.recording_uri",
                    "this token has no tenant, and with tenants in --tokens-file a job by reference "
                    "reads only its tenant's folder of the recordings root; use a token with a "
                    "tenant, or upload the recording");
      }
      const auto path = resolve_recording(spec_.recording_uri(), context_.recordings_root, tenant_);
      *response_ = context_.runner.submit(spec_, path.string(), tenant_);
      finish_locked(grpc::Status::OK);
      return;
    }
    if (!spec_.upload()) throw_invalid("spec.source", "neither recording_uri nor upload is set");
    // Refused before the client sends the recording, rather than after it.
    if (const std::string problem = context_.runner.store_problem(); !problem.empty()) {
      throw StoreUnavailable("the job store does not take writes now, retry later: " + problem);
    }
  } catch (const Error& error) {
    finish_locked(to_status(error));
    return;
  }
  const Admission admission = context_.registry.try_admit(tenant_);
  if (!admission.id) {
    log_event("info", "upload_refused", {{"reason", admission.tenant_full ? "tenant_max_sessions" : "max_sessions"}});
    finish_locked(grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED, context_.registry.busy_message(admission)));
    return;
  }
  slot_ = admission.id;
  context_.registry.watch(*slot_, weak_from_this());
  try {
    spool_ =
        std::make_unique<UploadSpool>(context_.spool_dir / (random_hex_id() + ".pfchunks"), context_.max_upload_bytes,
                                      session::PipelineOptions{}.max_item_errors, context_.spool_quota);
  } catch (const Error& error) {
    finish_locked(to_status(error));
    return;
  }
  log_event("info", "upload_start", {{"session", std::to_string(*slot_)}});
  start_read_locked();
}

void SubmitJobCall::add_chunk() {
  // No read is pending while this runs, so request_ and spool_ are this thread's alone.
  std::optional<grpc::Status> refused;
  try {
    if (!request_.has_chunk()) {
      throw_invalid("chunk[" + std::to_string(spool_->chunks()) + "]",
                    "after the JobSpec an upload holds only SessionChunk messages");
    }
    spool_->add(request_.chunk());
  } catch (const Error& error) {
    refused = to_status(error);
  }
  std::lock_guard lock(mu_);
  if (finished_) return;
  if (refused) {
    finish_locked(std::move(*refused));
    return;
  }
  request_.Clear();
  start_read_locked();
}

void SubmitJobCall::commit() {
  std::lock_guard lock(mu_);
  if (finished_) return;
  if (cancelled_) {
    finish_locked(grpc::Status(grpc::StatusCode::CANCELLED, "upload cancelled"));
    return;
  }
  try {
    // The store may take the bytes into itself (PostgreSQL: every replica reads them there).
    const std::filesystem::path spooled = spool_->commit();
    std::string recording;
    try {
      recording = context_.runner.store().keep_upload(spooled);
    } catch (const Error&) {
      std::error_code ignored;
      std::filesystem::remove(spooled, ignored);  // no job will read it
      throw;
    }
    try {
      *response_ = context_.runner.submit(spec_, recording, tenant_);
    } catch (const Error&) {
      try {
        context_.runner.store().drop_upload(recording, context_.spool_dir);
      } catch (const std::exception&) {
        // The error to report is the one that got us here.
      }
      throw;
    }
  } catch (const Error& error) {
    finish_locked(to_status(error));
    return;
  }
  log_event("info", "upload_end",
            {{"session", std::to_string(*slot_)},
             {"job", response_->job_id()},
             {"chunks", std::to_string(spool_->chunks())},
             {"bytes", std::to_string(spool_->bytes())}});
  finish_locked(grpc::Status::OK);
}

void SubmitJobCall::finish_locked(grpc::Status status) {
  if (finished_) return;
  finished_ = true;
  if (spool_ && !status.ok()) {
    log_event("info", "upload_refused",
              {{"session", std::to_string(*slot_)},
               {"status", status_code_name(status.error_code())},
               {"chunks", std::to_string(spool_->chunks())}});
  }
  spool_.reset();  // an upload that did not become a job leaves no file
  context_.metrics.job_submit_finished(tenant_, status_code_name(status.error_code()));
  Finish(std::move(status));
}

void SubmitJobCall::OnCancel() {
  std::lock_guard lock(mu_);
  cancelled_ = true;  // a pending read fails now; commit() sees the flag
}

void SubmitJobCall::check_idle(Clock::time_point now) {
  std::lock_guard lock(mu_);
  if (finished_ || !read_pending_ || now - last_read_at_ < context_.idle_timeout) return;
  log_event("info", "upload_idle", {{"session", std::to_string(*slot_)}});
  finish_locked(grpc::Status(
      grpc::StatusCode::DEADLINE_EXCEEDED,
      "no message from the client for " + std::to_string(context_.idle_timeout.count()) + " s (idle timeout)"));
}

void SubmitJobCall::OnDone() {
  std::shared_ptr<SubmitJobCall> keep_until_return;
  std::optional<std::uint64_t> slot;
  {
    std::lock_guard lock(mu_);
    keep_until_return = std::move(self_);
    slot = slot_;
  }
  if (slot) context_.registry.release(*slot);
}

}  // namespace posefuse::server
