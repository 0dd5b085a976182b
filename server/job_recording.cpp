#include "server/job_recording.hpp"

#include "common/error.hpp"
#include "session/chunk_file.hpp"
#include "session/directory_reader.hpp"
#include "session/recording_file.hpp"

namespace posefuse::server {

namespace fs = std::filesystem;

namespace {

// The recording, opened beneath the root. resolve_recording stored its path below the root's
// canonical form.
session::UniqueFd open_under_root(const fs::path& recording, const fs::path& root, const std::string& field) {
  if (root.empty()) {
    throw Error(ErrorCode::kFailedPrecondition, field,
                "the server was started without --recordings-root; submit by reference is off");
  }
  const fs::path canonical_root = fs::weakly_canonical(root);
  const fs::path relative = recording.lexically_relative(canonical_root);
  if (relative.empty() || *relative.begin() == "..") {
    throw_invalid(field, "is outside the server's recordings root");
  }
  const session::UniqueFd root_directory = session::open_path(canonical_root, "--recordings-root");
  return session::open_beneath(root_directory.get(), relative.string(), field);
}

}  // namespace

std::unique_ptr<session::ChunkSource> open_job_recording(const JobRecord& record, const fs::path& recordings_root) {
  const bool by_reference = !record.job.recording_uri().empty();
  const std::string field = by_reference ? "spec.recording_uri" : "recording";
  session::UniqueFd opened = by_reference ? open_under_root(record.recording_path, recordings_root, field)
                                          : session::open_path(record.recording_path, field);
  switch (session::file_kind(opened.get())) {
    case session::FileKind::kDirectory: return std::make_unique<session::DirectoryReader>(std::move(opened), field);
    case session::FileKind::kRegular: return std::make_unique<session::ChunkFileReader>(std::move(opened), field);
    default:
      throw_invalid(field,
                    "is neither a regular file nor a directory (FIFOs, devices and "
                    "sockets are refused)");
  }
}

}  // namespace posefuse::server
