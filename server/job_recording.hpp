#pragma once
// Opens the recording a job reads. A recording submitted by reference lies in its tenant's
// folder of the recordings root and is opened beneath that folder, without following any link
// on the way (session/recording_file.hpp), so that nothing changed under the root after
// submission can point the job outside it or into another tenant's folder; an uploaded one is
// the server's own spooled chunk file. Either way only a regular file (a chunk file) or a
// directory (a recording directory) is read: a FIFO would block the job forever.
//
// Tenant folders (docs/server.md "Security"): tenant T's recordings are <root>/T/...; the tenant
// "" (tokens without a tenant, or no tokens file) has the root itself. The submitting call
// decides whether "" may submit by reference at all (not when the tokens file names tenants).
#include <filesystem>
#include <memory>
#include <string>

#include "server/job_store.hpp"
#include "session/chunk_stream.hpp"

namespace posefuse::server {

// Resolves a submitted recording_uri ("path" or "file://path", relative to the tenant's folder;
// a leading '/' is ignored) to the path stored with the job, checking that it opens beneath
// `tenant`'s folder of `root`. Throws posefuse::Error naming "spec.recording_uri":
// kFailedPrecondition when root is empty (submission by reference is off), kInvalidArgument for
// an empty URI, a name with "..", or a link on the way, kNotFound when it (or the tenant's
// folder) does not exist. Another tenant's recording is not in the caller's folder, so it is
// answered exactly like a missing one.
std::filesystem::path resolve_recording(const std::string& uri, const std::filesystem::path& root,
                                        const std::string& tenant);

// Throws posefuse::Error naming "spec.recording_uri" (by reference) or "recording" (upload):
// kNotFound when missing, kInvalidArgument for a link, a path outside the owner's folder, or
// something that is neither a regular file nor a directory.
std::unique_ptr<session::ChunkSource> open_job_recording(const JobRecord& record,
                                                         const std::filesystem::path& recordings_root);

}  // namespace posefuse::server
