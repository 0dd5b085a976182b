#include "server/job_recording.hpp"

#include "common/error.hpp"
#include "session/chunk_file.hpp"
#include "session/directory_reader.hpp"
#include "session/recording_file.hpp"

namespace posefuse::server {

namespace fs = std::filesystem;

namespace {

constexpr const char* kUriField = "spec.recording_uri";

fs::path canonical_recordings_root(const fs::path& root, const std::string& field) {
  if (root.empty()) {
    throw Error(ErrorCode::kFailedPrecondition, field,
                "the server was started without --recordings-root; submit by reference is off");
  }
  return fs::weakly_canonical(root);
}

fs::path tenant_folder(const fs::path& canonical_root, const std::string& tenant) {
  return tenant.empty() ? canonical_root : canonical_root / tenant;
}

// `relative` opened beneath the tenant's folder, itself opened beneath the root: a ".." in
// `relative` can leave neither, so one tenant never reaches another's folder through it.
session::UniqueFd open_in_tenant_folder(const fs::path& canonical_root, const std::string& tenant,
                                        const std::string& relative, const std::string& field) {
  const session::UniqueFd root_directory = session::open_path(canonical_root, "--recordings-root");
  if (tenant.empty()) return session::open_beneath(root_directory.get(), relative, field);
  // A missing tenant folder (or a file in its place: ENOTDIR) reads as a missing recording.
  const session::UniqueFd folder = session::open_beneath(root_directory.get(), tenant, field);
  return session::open_beneath(folder.get(), relative, field);
}

}  // namespace

fs::path resolve_recording(const std::string& uri, const fs::path& root, const std::string& tenant) {
  const fs::path canonical_root = canonical_recordings_root(root, kUriField);
  std::string path = uri;
  if (path.rfind("file://", 0) == 0) path = path.substr(7);
  fs::path relative = fs::path(path).relative_path().lexically_normal();
  if (!relative.empty() && !relative.has_filename()) relative = relative.parent_path();  // "rec/"
  if (relative.empty()) throw_invalid(kUriField, "is empty");
  // Opening it is the check: the same rules, beneath the same folder, as the job's run.
  open_in_tenant_folder(canonical_root, tenant, relative.string(), kUriField);
  return tenant_folder(canonical_root, tenant) / relative;
}

std::unique_ptr<session::ChunkSource> open_job_recording(const JobRecord& record, const fs::path& recordings_root) {
  const bool by_reference = !record.job.recording_uri().empty();
  const std::string field = by_reference ? kUriField : "recording";
  session::UniqueFd opened;
  if (by_reference) {
    // resolve_recording stored the path below the owner's folder of the root's canonical form.
    const fs::path canonical_root = canonical_recordings_root(recordings_root, field);
    const fs::path relative =
        fs::path(record.recording_path).lexically_relative(tenant_folder(canonical_root, record.owner));
    if (relative.empty() || *relative.begin() == "..") {
      throw_invalid(field, "is outside its tenant's folder of the server's recordings root");
    }
    opened = open_in_tenant_folder(canonical_root, record.owner, relative.string(), field);
  } else {
    opened = session::open_path(record.recording_path, field);
  }
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
