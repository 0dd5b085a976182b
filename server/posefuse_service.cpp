#include "server/posefuse_service.hpp"

#include <google/protobuf/stubs/common.h>

#include "server/fit_session.hpp"
#include "server/job_calls.hpp"
#include "server/job_limits.hpp"
#include "server/log.hpp"
#include "server/refused_call.hpp"
#include "server/session_memory.hpp"
#include "server/status.hpp"
#include "session/option_table.hpp"
#include "session/session_validator.hpp"
#include "session/stages/default_stages.hpp"

namespace posefuse::server {

namespace {

grpc::Status jobs_off() {
  return grpc::Status(grpc::StatusCode::FAILED_PRECONDITION,
                      "batch jobs are off: the server was started without --data-dir");
}

grpc::ServerUnaryReactor* finish_unary(grpc::CallbackServerContext* context, grpc::Status status) {
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  reactor->Finish(std::move(status));
  return reactor;
}

}  // namespace

PoseFuseService::PoseFuseService(const ServerOptions& options, WorkerPool& pool, SessionRegistry& registry,
                                 Metrics& metrics, JobRunner* jobs, const BearerTokens* tokens)
    : options_(options),
      pool_(pool),
      registry_(registry),
      metrics_(metrics),
      jobs_(jobs),
      tokens_(tokens),
      spool_quota_(static_cast<std::uint64_t>(options_.max_spool_mb * 1024 * 1024)) {
  if (jobs_) {
    submit_context_.emplace(SubmitJobContext{*jobs_, pool_, registry_, metrics_, options_.recordings_root,
                                             tokens_ && tokens_->names_tenants(), upload_spool_dir(options_.data_dir),
                                             static_cast<std::uint64_t>(options_.max_upload_mb * 1024 * 1024),
                                             spool_quota_, std::chrono::duration<double>(options_.idle_timeout_s)});
  }
}

grpc::Status PoseFuseService::authenticate(const grpc::CallbackServerContext* context, const char* call,
                                           std::string& tenant) const {
  if (options_.role == "worker") {
    return grpc::Status(grpc::StatusCode::FAILED_PRECONDITION,
                        "this replica only runs jobs (--role worker); call an API replica");
  }
  return authenticate_call(tokens_, *context, call, tenant);
}

grpc::ServerBidiReactor<v1::SessionChunk, v1::FitResult>* PoseFuseService::Fit(grpc::CallbackServerContext* context) {
  std::string tenant;  // a Fit call keeps nothing, but takes one of its tenant's session slots and counts for it
  if (grpc::Status denied = authenticate(context, "Fit", tenant); !denied.ok()) {
    return new RefusedCall<grpc::ServerBidiReactor<v1::SessionChunk, v1::FitResult>>(denied);
  }
  const Admission admission = registry_.try_admit(tenant);
  if (!admission.id) {
    metrics_.session_refused(tenant);
    log_event("info", "session_refused",
              {{"reason", admission.tenant_full ? "tenant_max_sessions" : "max_sessions"}, {"peer", context->peer()}});
    return new RefusedCall<grpc::ServerBidiReactor<v1::SessionChunk, v1::FitResult>>(
        grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED, registry_.busy_message(admission)));
  }
  return FitSession::start(context, *admission.id, tenant, options_, pool_, registry_, metrics_);
}

grpc::ServerUnaryReactor* PoseFuseService::GetServerInfo(grpc::CallbackServerContext* context,
                                                         const v1::GetServerInfoRequest*, v1::ServerInfo* response) {
  std::string tenant;
  if (grpc::Status denied = authenticate(context, "GetServerInfo", tenant); !denied.ok()) {
    return finish_unary(context, denied);
  }
  *response = server_info(options_, static_cast<unsigned>(pool_.threads()), jobs_ != nullptr);
  return finish_unary(context, grpc::Status::OK);
}

grpc::ServerReadReactor<v1::SubmitJobRequest>* PoseFuseService::SubmitJob(grpc::CallbackServerContext* context,
                                                                          v1::Job* response) {
  std::string tenant;
  if (grpc::Status denied = authenticate(context, "SubmitJob", tenant); !denied.ok()) {
    return new RefusedCall<grpc::ServerReadReactor<v1::SubmitJobRequest>>(denied);
  }
  if (!jobs_) return new RefusedCall<grpc::ServerReadReactor<v1::SubmitJobRequest>>(jobs_off());
  return SubmitJobCall::start(*submit_context_, response, tenant);
}

grpc::ServerUnaryReactor* PoseFuseService::GetJob(grpc::CallbackServerContext* context,
                                                  const v1::GetJobRequest* request, v1::Job* response) {
  std::string tenant;
  if (grpc::Status denied = authenticate(context, "GetJob", tenant); !denied.ok()) {
    return finish_unary(context, denied);
  }
  if (!jobs_) return finish_unary(context, jobs_off());
  try {
    const auto record = jobs_->store().get(request->job_id());
    // Another tenant's job is answered exactly like a missing one.
    if (!record || record->owner != tenant) {
      return finish_unary(context,
                          grpc::Status(grpc::StatusCode::NOT_FOUND, "job_id: no job '" + request->job_id() + "'"));
    }
    *response = record->job;
    bound_stored_job(*response);
  } catch (const Error& error) {  // the job store failed
    return finish_unary(context, to_status(error));
  }
  return finish_unary(context, grpc::Status::OK);
}

grpc::ServerUnaryReactor* PoseFuseService::ListJobs(grpc::CallbackServerContext* context,
                                                    const v1::ListJobsRequest* request,
                                                    v1::ListJobsResponse* response) {
  std::string tenant;
  if (grpc::Status denied = authenticate(context, "ListJobs", tenant); !denied.ok()) {
    return finish_unary(context, denied);
  }
  if (!jobs_) return finish_unary(context, jobs_off());
  const std::size_t page_size = effective_page_size(request->page_size());
  std::vector<v1::Job::State> states;
  for (const int state : request->states()) states.push_back(static_cast<v1::Job::State>(state));
  try {
    // One more than asked for tells whether another page exists.
    std::vector<v1::Job> jobs = jobs_->store().list(page_size + 1, request->page_token(), states, tenant);
    // A page ends at page_size jobs or kMaxPageBytes, whichever comes first (always at least
    // one job, so that a listing makes progress).
    std::size_t bytes = 0;
    for (v1::Job& job : jobs) {
      bound_stored_job(job);
      bytes += job.ByteSizeLong();
      const std::size_t listed = static_cast<std::size_t>(response->jobs_size());
      if (listed == page_size || (listed > 0 && bytes > kMaxPageBytes)) {
        response->set_next_page_token(response->jobs(response->jobs_size() - 1).job_id());
        break;
      }
      *response->add_jobs() = std::move(job);
    }
  } catch (const Error& error) {
    return finish_unary(context, to_status(error));
  }
  return finish_unary(context, grpc::Status::OK);
}

grpc::ServerUnaryReactor* PoseFuseService::CancelJob(grpc::CallbackServerContext* context,
                                                     const v1::CancelJobRequest* request, v1::Job* response) {
  std::string tenant;
  if (grpc::Status denied = authenticate(context, "CancelJob", tenant); !denied.ok()) {
    return finish_unary(context, denied);
  }
  if (!jobs_) return finish_unary(context, jobs_off());
  try {
    const auto job = jobs_->cancel(request->job_id(), tenant);
    if (!job) {
      return finish_unary(context,
                          grpc::Status(grpc::StatusCode::NOT_FOUND, "job_id: no job '" + request->job_id() + "'"));
    }
    *response = *job;
    bound_stored_job(*response);
  } catch (const Error& error) {  // the job store failed
    return finish_unary(context, to_status(error));
  }
  return finish_unary(context, grpc::Status::OK);
}

grpc::ServerWriteReactor<v1::Job>* PoseFuseService::WatchJob(grpc::CallbackServerContext* context,
                                                             const v1::WatchJobRequest* request) {
  std::string tenant;
  if (grpc::Status denied = authenticate(context, "WatchJob", tenant); !denied.ok()) {
    return new RefusedCall<grpc::ServerWriteReactor<v1::Job>>(denied);
  }
  if (!jobs_) return new RefusedCall<grpc::ServerWriteReactor<v1::Job>>(jobs_off());
  return watch_job(*jobs_, request->job_id(), tenant);
}

grpc::ServerWriteReactor<v1::FitResult>* PoseFuseService::GetJobResults(grpc::CallbackServerContext* context,
                                                                        const v1::GetJobResultsRequest* request) {
  std::string tenant;
  if (grpc::Status denied = authenticate(context, "GetJobResults", tenant); !denied.ok()) {
    return new RefusedCall<grpc::ServerWriteReactor<v1::FitResult>>(denied);
  }
  if (!jobs_) return new RefusedCall<grpc::ServerWriteReactor<v1::FitResult>>(jobs_off());
  return job_results(*jobs_, request->job_id(), tenant);
}

v1::ServerInfo server_info(const ServerOptions& options, unsigned workers, bool jobs) {
  v1::ServerInfo info;
  info.set_server_version(POSEFUSE_VERSION);
  info.set_api_version("posefuse.v1");
  info.add_session_format_versions(session::kFormatVersion);
  info.set_grpc_version(grpc::Version());
  info.set_protobuf_version(google::protobuf::internal::VersionString(GOOGLE_PROTOBUF_VERSION));
  for (const auto& stage : session::make_default_stages()) {
    v1::StageInfo& stage_info = *info.add_stages();
    stage_info.set_name(std::string(stage->name()));
    stage_info.set_description(std::string(stage->description()));
    for (const session::OptionSpec& option : stage->options()) {
      v1::OptionInfo& option_info = *info.add_options();
      option_info.set_key(option.key);
      option_info.set_stage(std::string(stage->name()));
      option_info.set_default_value(option.default_value);
      // OptionInfo has no fields for them: the values and the unit follow the description.
      option_info.set_description(option.description + " [" + session::describe_values_and_unit(option) + "]");
    }
  }
  // No body model is loaded yet (core/body lands later); the list stays empty until then.
  v1::ServerLimits& limits = *info.mutable_limits();
  limits.set_max_message_bytes(static_cast<std::uint64_t>(options.max_message_mb * 1024 * 1024));
  limits.set_max_sessions(options.max_sessions);
  limits.set_max_queued_chunks(options.max_queued_chunks);
  limits.set_idle_timeout_s(options.idle_timeout_s);
  limits.set_workers(workers);
  limits.set_max_upload_bytes(static_cast<std::uint64_t>(options.max_upload_mb * 1024 * 1024));
  limits.set_max_session_memory_bytes(session_memory_bytes(options));
  info.set_jobs_supported(jobs);
  return info;
}

}  // namespace posefuse::server
