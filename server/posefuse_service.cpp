#include "server/posefuse_service.hpp"

#include <google/protobuf/stubs/common.h>

#include "server/fit_session.hpp"
#include "server/log.hpp"
#include "session/session_validator.hpp"
#include "session/stages/default_stages.hpp"

namespace posefuse::server {

namespace {

// Refuses a Fit call at once (over the session limit).
class RefusedFit : public grpc::ServerBidiReactor<v1::SessionChunk, v1::FitResult> {
 public:
  explicit RefusedFit(grpc::Status status) { Finish(std::move(status)); }
  void OnDone() override { delete this; }
};

}  // namespace

PoseFuseService::PoseFuseService(const ServerOptions& options, WorkerPool& pool,
                                 SessionRegistry& registry)
    : options_(options), pool_(pool), registry_(registry) {}

grpc::ServerBidiReactor<v1::SessionChunk, v1::FitResult>* PoseFuseService::Fit(
    grpc::CallbackServerContext* context) {
  const std::optional<std::uint64_t> id = registry_.try_admit();
  if (!id) {
    log_event("info", "session_refused", {{"reason", "max_sessions"}, {"peer", context->peer()}});
    return new RefusedFit(grpc::Status(
        grpc::StatusCode::RESOURCE_EXHAUSTED,
        "server busy: " + std::to_string(options_.max_sessions) +
            " sessions are running (--max-sessions); retry later"));
  }
  return FitSession::start(context, *id, options_, pool_, registry_);
}

grpc::ServerUnaryReactor* PoseFuseService::GetServerInfo(grpc::CallbackServerContext* context,
                                                         const v1::GetServerInfoRequest*,
                                                         v1::ServerInfo* response) {
  *response = server_info(options_, static_cast<unsigned>(pool_.threads()));
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  reactor->Finish(grpc::Status::OK);
  return reactor;
}

v1::ServerInfo server_info(const ServerOptions& options, unsigned workers) {
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
    for (const session::StageOption& option : stage->options()) {
      v1::OptionInfo& option_info = *info.add_options();
      option_info.set_key(option.key);
      option_info.set_stage(std::string(stage->name()));
      option_info.set_default_value(option.default_value);
      option_info.set_description(option.description);
    }
  }
  // No body model is loaded yet (core/body lands later); the list stays empty until then.
  v1::ServerLimits& limits = *info.mutable_limits();
  limits.set_max_message_bytes(static_cast<std::uint64_t>(options.max_message_mb * 1024 * 1024));
  limits.set_max_sessions(options.max_sessions);
  limits.set_max_queued_chunks(options.max_queued_chunks);
  limits.set_idle_timeout_s(options.idle_timeout_s);
  limits.set_workers(workers);
  info.set_jobs_supported(false);
  return info;
}

}  // namespace posefuse::server
