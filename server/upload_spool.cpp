#include "server/upload_spool.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <iomanip>
#include <sstream>
#include <system_error>

#include "common/error.hpp"
#include "session/recording_file.hpp"

namespace posefuse::server {

namespace {

constexpr const char* kPartialSuffix = ".partial";

// Waits until what `path` (a file or a directory) holds is on the disk. A full disk is
// RESOURCE_EXHAUSTED, as the job store's own writes are.
void sync_to_disk(const std::filesystem::path& path) {
  const session::UniqueFd fd = session::open_path(path, "upload");
  if (::fsync(fd.get()) != 0) {
    const int error = errno;
    throw Error(error == ENOSPC || error == EDQUOT ? ErrorCode::kResourceExhausted : ErrorCode::kInternal, "upload",
                std::string("cannot write the spooled upload to disk: ") + std::strerror(error));
  }
}

// Bytes as MiB the way the flag was given: "8192", "0.75".
std::string mib_text(std::uint64_t bytes) {
  std::ostringstream text;
  text << std::setprecision(6) << static_cast<double>(bytes) / (1024.0 * 1024.0);
  return text.str();
}

}  // namespace

std::filesystem::path UploadSpool::partial_path(const std::filesystem::path& final_path) {
  std::filesystem::path partial = final_path;
  partial += kPartialSuffix;
  return partial;
}

UploadSpool::UploadSpool(std::filesystem::path final_path, std::uint64_t max_bytes, std::uint64_t max_rejected_chunks,
                         SpoolQuota& quota)
    : final_path_(std::move(final_path)),
      partial_path_(partial_path(final_path_)),
      max_bytes_(max_bytes),
      max_rejected_(max_rejected_chunks),
      quota_(quota),
      writer_(std::make_unique<session::ChunkFileWriter>(partial_path_)) {}

UploadSpool::~UploadSpool() {
  writer_.reset();
  quota_.release(bytes_);
  if (!committed_) {
    std::error_code ignored;
    std::filesystem::remove(partial_path_, ignored);
  }
}

void UploadSpool::add(const v1::SessionChunk& chunk) {
  const std::string field = "chunk[" + std::to_string(chunks_) + "]";
  if (ended_) throw_invalid(field, "chunk after the end marker (a session ends with exactly one)");
  // The file's length prefix is at most 10 bytes; counting it keeps the bound exact enough.
  const std::uint64_t size = chunk.ByteSizeLong() + 10;
  if (bytes_ + size > max_bytes_) {
    throw Error(
        ErrorCode::kResourceExhausted, "upload",
        "larger than the server's limit of " + std::to_string(max_bytes_ >> 20) + " MiB (--max-upload-mb) at " + field);
  }
  try {
    validator_.check(chunk);
  } catch (const Error&) {
    // Without a valid header nothing else can be interpreted (as in SessionPipeline::push).
    if (!validator_.has_header()) throw;
    if (++rejected_ > max_rejected_) {
      throw Error(ErrorCode::kInvalidArgument, "chunks",
                  std::to_string(rejected_) + " chunks rejected (limit " + std::to_string(max_rejected_) +
                      "); the last at " + field);
    }
  }
  // After the checks above, which end the upload without writing the chunk.
  if (!quota_.try_reserve(size)) {
    throw Error(ErrorCode::kResourceExhausted, "upload",
                "the uploads in transit together would pass the server's spool quota of " +
                    mib_text(quota_.max_bytes()) + " MiB (--max-spool-mb) at " + field + "; retry later");
  }
  bytes_ += size;  // reserved: given back by the destructor, whatever happens next
  if (chunk.has_end()) ended_ = true;
  writer_->write(chunk);
  ++chunks_;
}

const std::filesystem::path& UploadSpool::commit() {
  if (!ended_) {
    throw_invalid("end", "the upload stopped after " + std::to_string(chunks_) +
                             " chunks without the end marker (truncated upload)");
  }
  writer_->finish();
  writer_.reset();
  // The job row that names the file comes next and survives a crash: the file's bytes, then its
  // name (the directory's entry), reach the disk before it.
  sync_to_disk(partial_path_);
  std::error_code error;
  std::filesystem::rename(partial_path_, final_path_, error);
  if (error) {
    throw Error(ErrorCode::kInternal, "upload", "cannot move the spooled upload into place: " + error.message());
  }
  try {
    sync_to_disk(final_path_.parent_path());
  } catch (const Error&) {
    std::filesystem::remove(final_path_, error);  // no job will name it
    throw;
  }
  committed_ = true;
  return final_path_;
}

std::size_t remove_partial_uploads(const std::filesystem::path& spool_dir) {
  std::size_t removed = 0;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(spool_dir, error)) {
    if (entry.path().extension() == kPartialSuffix) {
      std::error_code ignored;
      removed += std::filesystem::remove(entry.path(), ignored) ? 1 : 0;
    }
  }
  return removed;
}

}  // namespace posefuse::server
