#pragma once
// Opens the recording a job reads. A recording submitted by reference is opened beneath the
// recordings root, without following any link on the way (session/recording_file.hpp), so
// that nothing changed under the root after submission can point the job outside it; an
// uploaded one is the server's own spooled chunk file. Either way only a regular file (a chunk
// file) or a directory (a recording directory) is read: a FIFO would block the job forever.
#include <filesystem>
#include <memory>

#include "server/job_store.hpp"
#include "session/chunk_stream.hpp"

namespace posefuse::server {

// Throws posefuse::Error naming "spec.recording_uri" (by reference) or "recording" (upload):
// kNotFound when missing, kInvalidArgument for a link, a path outside the root, or something
// that is neither a regular file nor a directory.
std::unique_ptr<session::ChunkSource> open_job_recording(const JobRecord& record,
                                                         const std::filesystem::path& recordings_root);

}  // namespace posefuse::server
