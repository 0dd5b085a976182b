#pragma once
// The batch-job calls of posefuse.v1.PoseFuse that stream (WatchJob, GetJobResults) on the
// callback API, over a JobRunner, and the resolution of a recording submitted by reference
// (SubmitJob itself: submit_job_call.hpp).
#include <filesystem>
#include <string>

#include <grpcpp/grpcpp.h>

#include "posefuse/v1/service.grpc.pb.h"
#include "server/job_runner.hpp"

namespace posefuse::server {

// Resolves a submitted recording_uri ("path" or "file://path") against `root`; the result must
// stay inside root. Throws posefuse::Error: kFailedPrecondition when root is empty (submission
// by reference disabled), kInvalidArgument for a path outside root, kNotFound when missing.
std::filesystem::path resolve_recording(const std::string& uri, const std::filesystem::path& root);

// Both answer NOT_FOUND for a job of another tenant than `tenant`, as for a missing one.
grpc::ServerWriteReactor<v1::Job>* watch_job(JobRunner& runner, const std::string& job_id, const std::string& tenant);
grpc::ServerWriteReactor<v1::FitResult>* job_results(JobRunner& runner, const std::string& job_id,
                                                     const std::string& tenant);

}  // namespace posefuse::server
