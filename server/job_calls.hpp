#pragma once
// The batch-job calls of posefuse.v1.PoseFuse (SubmitJob, GetJob, ListJobs, CancelJob,
// WatchJob, GetJobResults) on the callback API, over a JobRunner.
#include <filesystem>
#include <string>

#include <grpcpp/grpcpp.h>

#include "posefuse/v1/service.grpc.pb.h"
#include "server/job_runner.hpp"
#include "server/worker_pool.hpp"

namespace posefuse::server {

// Resolves a submitted recording_uri ("path" or "file://path") against `root`; the result must
// stay inside root. Throws posefuse::Error: kFailedPrecondition when root is empty (submission
// by reference disabled), kInvalidArgument for a path outside root, kNotFound when missing.
std::filesystem::path resolve_recording(const std::string& uri, const std::filesystem::path& root);

// Where uploaded recordings are spooled: <data_dir>/uploads.
inline std::filesystem::path upload_spool_dir(const std::string& data_dir) {
  return std::filesystem::path(data_dir) / "uploads";
}

// What SubmitJob needs; lives as long as the service.
struct SubmitJobContext {
  JobRunner& runner;
  WorkerPool& pool;
  std::filesystem::path recordings_root;  // by reference: empty = off
  std::filesystem::path spool_dir;        // by upload: where the chunk files go
  std::uint64_t max_upload_bytes;
};

// By reference: resolves the recording and stores the job. By upload: spools the chunks that
// follow the spec (UploadSpool) and stores the job once the whole session has arrived.
grpc::ServerReadReactor<v1::SubmitJobRequest>* submit_job(const SubmitJobContext& context,
                                                          v1::Job* response);
grpc::ServerWriteReactor<v1::Job>* watch_job(JobRunner& runner, const std::string& job_id);
grpc::ServerWriteReactor<v1::FitResult>* job_results(JobRunner& runner, const std::string& job_id);

}  // namespace posefuse::server
