#pragma once
// The batch-job calls of posefuse.v1.PoseFuse that stream (WatchJob, GetJobResults) on the
// callback API, over a JobRunner (SubmitJob: submit_job_call.hpp).
#include <string>

#include <grpcpp/grpcpp.h>

#include "posefuse/v1/service.grpc.pb.h"
#include "server/job_runner.hpp"

namespace posefuse::server {

// Both answer NOT_FOUND for a job of another tenant than `tenant`, as for a missing one.
grpc::ServerWriteReactor<v1::Job>* watch_job(JobRunner& runner, const std::string& job_id, const std::string& tenant);
grpc::ServerWriteReactor<v1::FitResult>* job_results(JobRunner& runner, const std::string& job_id,
                                                     const std::string& tenant);

}  // namespace posefuse::server
