#pragma once
// The disk side of SubmitJob by upload: the session's chunks, validated one by one as they
// arrive, appended to a chunk file in the job store's spool folder (disk, never memory: one
// chunk at a time is held). Only a whole session becomes a job: commit() checks that the end
// marker came and moves the file to its final name; an upload that is abandoned (truncated,
// refused, cancelled) leaves nothing behind.
//
// Validation follows SessionPipeline's rules, so that an upload is refused exactly when Fit would
// have ended the same stream, and a job sees what Fit would have seen:
//  - session-ending (INVALID_ARGUMENT, the upload stops): no or an invalid header, a chunk after
//    the end marker, more than max_rejected_chunks chunks that fail validation, a stream that
//    stops without the end marker;
//  - a data chunk that fails validation is kept (the job reports it as an ItemError, as Fit
//    does) but does not advance the validator.
// Size: more than max_bytes in all, or more than the spool quota leaves to the uploads in transit
// together, is RESOURCE_EXHAUSTED (field "upload").
#include <cstdint>
#include <filesystem>
#include <memory>

#include "posefuse/v1/session.pb.h"
#include "server/spool_quota.hpp"
#include "session/chunk_file.hpp"
#include "session/session_validator.hpp"

namespace posefuse::server {

class UploadSpool {
 public:
  // Writes to `<final_path>.partial` until commit(); each chunk's bytes are reserved in `quota`
  // first.
  UploadSpool(std::filesystem::path final_path, std::uint64_t max_bytes, std::uint64_t max_rejected_chunks,
              SpoolQuota& quota);
  ~UploadSpool();  // removes the partial file unless committed; gives the quota back
  UploadSpool(const UploadSpool&) = delete;
  UploadSpool& operator=(const UploadSpool&) = delete;

  // The next chunk of the upload. Throws posefuse::Error when the upload cannot go on.
  void add(const v1::SessionChunk& chunk);
  // The client has sent everything: throws kInvalidArgument (field "end") without an end marker;
  // otherwise closes the file, moves it to final_path, waits until both its bytes and its name
  // are on the disk (fsync of the file, then of its folder) and returns final_path.
  // kResourceExhausted when the disk is full, kInternal for other failures (nothing is left).
  const std::filesystem::path& commit();

  std::uint64_t chunks() const { return chunks_; }
  std::uint64_t bytes() const { return bytes_; }
  std::uint64_t rejected_chunks() const { return rejected_; }

  // The partial file of a final path (what a server that stopped mid-upload leaves behind).
  static std::filesystem::path partial_path(const std::filesystem::path& final_path);

 private:
  std::filesystem::path final_path_;
  std::filesystem::path partial_path_;
  std::uint64_t max_bytes_;
  std::uint64_t max_rejected_;
  SpoolQuota& quota_;
  std::unique_ptr<session::ChunkFileWriter> writer_;
  session::SessionValidator validator_;
  bool ended_ = false;
  bool committed_ = false;
  std::uint64_t chunks_ = 0;
  std::uint64_t bytes_ = 0;
  std::uint64_t rejected_ = 0;
};

// Removes the partial files a stopped server left in `spool_dir`; returns how many.
std::size_t remove_partial_uploads(const std::filesystem::path& spool_dir);

}  // namespace posefuse::server
